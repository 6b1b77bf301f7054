// Moving a surface with the particles. A surface written by ctsurg-surface on a grid ties each vertex
// to the lattice (core/surface_mesh_file.h): the cell holding it with the trilinear weights of its 8
// corners, and the nearest inside node. The vertex follows the particles' displacements:
//
//   trilinear (default): v = v_rest + sum_c w_c (x_c - X_c) over the corners c that are particles,
//     with the weights renormalised over those corners (sum w_c = 1), so a rigid translation moves
//     the vertex exactly with it and zero displacement leaves it exactly at rest. A corner that is
//     not a particle (outside the tissue) has no displacement of its own and is left out rather than
//     counted as still; when no corner is a particle, the nearest-particle rule is used.
//   nearest particle: v = v_rest + (x_p - X_p), p = the particle at the vertex's nearest inside node
//     (the papers' one-particle-per-vertex mapping, Mosegaard & Sorensen 2005, section 2.6, applied to
//     the displacement so that the rest surface is kept).
//
// The surface's lattice must be the grid model's lattice, possibly padded by whole nodes (ctsurg-surface
// pads where the tissue touches the border): same spacing and direction, origin on a lattice node. The
// model enters as its lattice and its particles' cells (base/lattice_particles.h): SpringGridModel's
// `lattice` and `cells`.
//
// Units: LPS mm. The per-vertex kernel is src/surface_coupling_impl.h.
#pragma once

#include "ctsurg/core/image_geometry.h"
#include "ctsurg/core/surface_mesh_file.h"
#include "ctsurg/sim/base/particle_state.h"

#include <cstdint>
#include <vector>

namespace ctsurg::sim {

enum class CouplingMode { trilinear, nearest_particle };

struct SurfaceCoupling {
  CouplingMode mode = CouplingMode::trilinear;
  std::vector<int32_t> particles;   // #V x 8: the corners' particles (-1: not a particle, weight 0)
  std::vector<Real> weights;        // #V x 8: renormalised weights, sum 1 over present corners
  std::vector<Real> rest_vertices;  // #V x 3 LPS mm

  int64_t vertex_count() const { return static_cast<int64_t>(rest_vertices.size() / 3); }
};

// Builds the coupling of `mesh` to the lattice model whose particles sit in `particle_cells` (#P flat
// cell indices of `lattice`, increasing) (built once). In nearest-particle mode each vertex has one
// particle (slot 0, weight 1) and the other slots are empty. Throws InputError("surface", "lattice", ...)
// when the lattices do not match (see above), InputError("surface", "grid_cell", ...) when the tie is
// missing, and InputError("surface", "vertex N", ...) when a vertex has no particle to follow.
SurfaceCoupling couple_surface(const SurfaceMesh& mesh, const ImageGeometry& lattice, const std::vector<int64_t>& particle_cells,
                               CouplingMode mode = CouplingMode::trilinear);

// Writes the moved vertices (#V x 3 LPS mm, row-major, resized) from the particles' positions.
// rest_positions: the model's (#P x 3). On the host's arrays: parallel over vertices (OpenMP),
// deterministic, whatever backend the model runs on (a model on a CUDA device copies its state back
// first; DeviceSimulation also moves a surface on the device with the same kernel).
void move_surface(const SurfaceCoupling& coupling, const ParticleState& state, const std::vector<Real>& rest_positions,
                  std::vector<float>& vertices, int threads = 0);

}  // namespace ctsurg::sim
