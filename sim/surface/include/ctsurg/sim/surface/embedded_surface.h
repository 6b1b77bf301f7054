// The surface a model carries: the rendered surface's triangles and each vertex's tie to the model's
// nodes (a grid model's lattice cell: surface_coupling.h; a tet: tet_embedding.h). It follows the nodes'
// displacements (move) and is cut with the same blade as the model's springs (cut: crossed triangles
// removed, vertices detached from nodes across the blade; surface_cutting.h), so an incision opens on
// screen. With close_cuts, the holes a cut leaves are closed with new triangles over the existing
// vertices (hole_filling.h) so the surface stays closed for rendering and volume. A simulation engine (base/simulation_engine.h) keeps one with its model; empty when the
// scenario has no surface.
//
// Units: mm, in the engine's local frame.
#pragma once

#include "ctsurg/sim/base/particle_state.h"
#include "ctsurg/sim/base/tool_shapes.h"
#include "ctsurg/sim/surface/surface_coupling.h"

#include <cstdint>
#include <utility>
#include <vector>

namespace ctsurg::sim {

class EmbeddedSurface {
 public:
  EmbeddedSurface() = default;  // no surface
  // coupling: each vertex's nodes and weights (its rest_vertices are the surface's, #V x 3 mm);
  // triangles: #F x 3 vertex ids. Throws InputError("surface", "triangles", ...) for an id out of range.
  EmbeddedSurface(SurfaceCoupling coupling, std::vector<uint32_t> triangles);

  bool empty() const { return coupling_.rest_vertices.empty(); }
  int64_t vertex_count() const { return coupling_.vertex_count(); }
  // #F x 3, now: the uncut triangles, then (close_cuts) the triangles closing the cut holes.
  const std::vector<uint32_t>& triangles() const { return triangles_; }
  int64_t fill_triangle_count() const { return static_cast<int64_t>(triangles_.size() - cut_.size()) / 3; }
  const std::vector<Real>& rest_vertices() const { return coupling_.rest_vertices; }  // #V x 3 mm
  const SurfaceCoupling& coupling() const { return coupling_; }

  // The vertices (#V x 3 mm; resized) where the nodes at `positions` put them; `rest` (#P x 3 mm): the
  // nodes' rest positions (move_surface in surface_coupling.h).
  void move(const ParticleState& positions, const std::vector<Real>& rest, std::vector<float>& vertices, int threads) const;
  // Cuts along the blade triangle; `vertices` are the surface's now (move()) and `positions` the nodes'.
  // Returns the number of triangles removed.
  int64_t cut(const Triangle& blade, const std::vector<float>& vertices, const ParticleState& positions);
  // Removes the triangles crossing the blade, leaving the ties alone (remove_crossed_triangles).
  int64_t cut_triangles(const Triangle& blade, const std::vector<float>& vertices);
  // Removes the triangles with a vertex tied (weight > 0) to a node marked in `gone` (#P flags, 1 = the
  // tissue there was removed: a cautery, springs/particle_removal.h). Returns how many; the crater
  // stays open until close_cut_holes(). InputError("surface", "gone", ...) for a tie beyond `gone`.
  int64_t remove_tied_to(const std::vector<uint8_t>& gone);
  // Removes the triangles with a vertex flagged in `gone` (#V; an FEM model's vertices whose element was
  // removed). Returns how many; InputError("surface", "gone", ...) for a size that is not #V.
  int64_t remove_vertices(const std::vector<uint8_t>& gone);
  // Whether the holes cuts leave are closed (hole_filling.h); off by default. The surface's own
  // boundary (an open surface) is the one it has when this is switched on, and is never closed.
  void set_close_cuts(bool close);
  bool close_cuts() const { return close_cuts_; }
  // Re-closes every cut hole over `vertices` (#V x 3 mm, now: move()); call after a sweep's cuts. Does
  // nothing unless close_cuts. Returns the number of closing triangles.
  int64_t close_cut_holes(const std::vector<float>& vertices);
  // New node ids for every tie (#V x 8, as coupling().particles; weights kept): a model that split nodes
  // (fem/fem_cutting.h) moves each vertex to the copies of its own element. InputError on a size mismatch.
  void retie(std::vector<int32_t> particles);

 private:
  SurfaceCoupling coupling_;
  std::vector<uint32_t> cut_;        // #F x 3: the surface's triangles the cuts left
  std::vector<uint32_t> triangles_;  // cut_, then the closing triangles
  std::vector<uint32_t> weld_;       // hole_filling.h weld_coincident() of the rest vertices
  std::vector<std::pair<uint32_t, uint32_t>> own_boundary_;  // boundary_edges() before any cut (welded ids)
  bool close_cuts_ = false;
};

}  // namespace ctsurg::sim
