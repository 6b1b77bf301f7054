// Tangent frames that follow a deformation. The normal map was baked against the surface file's own
// normals and glTF tangents (ctsurg-normalmap), so those frames are kept and rotated with the tissue:
// at each vertex, the rotation taking the rest geometric frame to the deformed one is applied to the
// file's normal and tangent (the handedness w is kept).
//
// The geometric frame of a vertex is built from the triangles of the current topology around it, at
// rest and deformed alike: the area-weighted face normal g (summed over every copy of the vertex that
// atlas seams made, through /surface/source_vertex, so both sides of a seam turn together) and the
// texture derivative dP/du summed over the vertex's own triangles (as in tangent_frames.h). With
// F = [t, g x t, g] (t: dP/du made orthogonal to g), the rotation is R = F_deformed F_rest^T. Without
// usable uvs (no atlas, or a degenerate dP/du) R is the smallest rotation taking g_rest to g_deformed.
// An undeformed surface gives R = I exactly, so the rest picture shows the file's frames unchanged;
// a cut (fewer triangles) changes rest and deformed frames alike.
//
// Sequential scatter over triangles in order, then per vertex: deterministic.
#pragma once

#include <cstdint>
#include <map>
#include <vector>

#include "ctsurg/core/surface_mesh_file.h"

namespace ctsurg {

class DeformedTangentFrames {
 public:
  // `rest` must have normals; tangents and uvs are optional (then normals alone are rotated).
  explicit DeformedTangentFrames(const SurfaceMesh& rest);

  // vertices #V x 3 (LPS mm) deformed; triangles #T x 3 of the current topology, `topology` an id
  // for it (the rest frames of each topology are computed once and cached under that id).
  // Outputs: normals #V x 3 (unit), tangents #V x 4 (unit xyz, w = +-1; empty when the mesh has none).
  void compute(const float* vertices, const std::vector<uint32_t>& triangles, int topology, std::vector<float>& normals,
               std::vector<float>& tangents);

 private:
  struct GeometricFrames {
    std::vector<float> g;  // #V x 3, area-weighted normal sums (welded over seams)
    std::vector<float> t;  // #V x 3, dP/du sums (per vertex); empty without uvs
  };
  GeometricFrames geometric_frames(const float* vertices, const std::vector<uint32_t>& triangles) const;

  int64_t vertex_count_ = 0;
  std::vector<float> rest_vertices_, rest_normals_, rest_tangents_, uvs_;
  std::vector<uint32_t> weld_;   // #V: representative of each vertex's seam group
  std::map<int, GeometricFrames> rest_cache_;
};

}  // namespace ctsurg
