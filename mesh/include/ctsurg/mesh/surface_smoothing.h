// Taubin smoothing (G. Taubin, "A signal processing approach to fair surface design", SIGGRAPH 1995):
// alternating Laplacian steps of factor lambda > 0 (shrink) and mu < -lambda (inflate) form a
// low-pass filter that removes the marching-cubes staircase without the shrinkage of plain Laplacian
// smoothing. Pass band kPB = 1/lambda + 1/mu (Taubin's eq. 9); the defaults (lambda 0.5, kPB 0.1,
// so mu = -0.5263) are the paper's.
#pragma once

#include "ctsurg/core/surface_mesh_file.h"

namespace ctsurg {

struct TaubinOptions {
  int iterations = 10;        // lambda|mu step pairs, >= 0
  double lambda = 0.5;        // 0 < lambda < 1
  double pass_band = 0.1;     // kPB, 0 < kPB < 1/lambda; mu = 1 / (kPB - 1/lambda)
};

// Smooths mesh.vertices in place with the uniform ("umbrella") Laplacian over each vertex's one-ring
// of mesh edges; triangles are unchanged. Then recomputes mesh.normals as the angle-weighted
// normals of the smoothed triangles (unit, outward when the triangles are counter-clockwise from
// outside). The lattice tie is left as it was: call tie_surface_to_lattice() (lattice_tie.h) to make
// its weights reproduce the moved vertices.
//
// mesh  #V x 3 LPS mm vertices, #F x 3 triangles
// Throws InputError("--smooth", ...) for parameters out of range. Deterministic; parallel (OpenMP).
void taubin_smooth(SurfaceMesh& mesh, const TaubinOptions& options = {});

// Angle-weighted vertex normals of a triangle mesh (Thurmer & Wuthrich 1998): unit, #V x 3; a vertex
// in no non-degenerate triangle keeps its previous normal (or gets (0, 0, 0) when there was none).
void recompute_vertex_normals(SurfaceMesh& mesh);

}  // namespace ctsurg
