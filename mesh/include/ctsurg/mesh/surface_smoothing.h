// Smoothing of marching-cubes surfaces: two low-pass filters of the vertex positions over the
// uniform ("umbrella") Laplacian of the mesh edges, K = I - W with W the mean over each vertex's
// one-ring (eigenvalues k in [0, 2]; small k = smooth shape, large k = the voxel staircase), and the
// restoration of the enclosed volume afterwards.
//
// Taubin smoothing (G. Taubin, "A signal processing approach to fair surface design", SIGGRAPH 1995):
// alternating Laplacian steps of factor lambda > 0 (shrink) and mu < -lambda (inflate) form a
// low-pass filter that removes the marching-cubes staircase without the shrinkage of plain Laplacian
// smoothing. Pass band kPB = 1/lambda + 1/mu (Taubin's eq. 9); the defaults (lambda 0.5, kPB 0.1,
// so mu = -0.5263) are the paper's.
//
// Windowed-sinc smoothing (G. Taubin, T. Zhang, G. Golub, "Optimal surface smoothing as filter
// design", ECCV 1996 / IBM RC-20404; VTK's vtkWindowedSincPolyDataFilter, which 3D Slicer's
// segmentation export uses): the ideal low-pass filter f(k) = 1 for k <= kPB, 0 above, written in
// theta with k = 2 (1 - cos theta) and expanded in Chebyshev polynomials of x = 1 - k/2 = cos theta
// to order N: f(k) = sum_i c_i T_i(1 - k/2), c_0 = w_0 (theta_PB + sigma) / pi,
// c_i = 2 w_i sin(i (theta_PB + sigma)) / (i pi), theta_PB = acos(1 - kPB/2), with the Hamming window
// w_i = 0.54 + 0.46 cos(pi i / (N + 1)) against the Gibbs ripple. The pass band is widened by the
// smallest sigma >= 0 that gives f(kPB) = 1 (VTK finds it by Newton steps to |f - 1| < 1e-3; here by
// a scan and bisection, to 1e-12), and the c_i are then divided by their sum so that f(0) = 1
// exactly: a translation passes unchanged, so the result does not depend on where the surface sits
// (what VTK's NormalizeCoordinates option and its later Nuttall window are for; with the Hamming
// window alone VTK scales the surface by up to 1 %). Applied by the three-term recurrence
// x_0 = x, x_1 = M x_0, x_{i+1} = 2 M x_i - x_{i-1}, M = I - K/2, output sum_i c_i x_i: N Laplacian
// applications. Slicer's defaults: smoothing factor 0.5 -> kPB = 10^(-4 x 0.5) = 0.01, N = 20,
// boundary and feature-edge smoothing off (vertices on a border stay put), non-manifold smoothing on.
// Response of those defaults: f(0) = 1, f(0.01) = 0.999, f(0.05) = 0.88, f(0.1) = 0.62,
// f(0.2) = 0.18, |f| < 0.002 for k >= 0.5. Against VTK 9.1 with those settings on the heart grid's
// surface: VTK's result is this one scaled by its f(0) = 1.00116, to 0.017 mm mean (docs/mesh.md).
//
// Both filters shrink a curved surface a little (Taubin by the second order of its steps, the
// windowed sinc by f < 1 just below the pass band edge) and change its volume where they flatten the
// staircase. restore_enclosed_volume() moves every vertex by one common distance along its vertex
// normal so that the enclosed volume is the given one again (closed surfaces only).
#pragma once

#include "ctsurg/core/surface_mesh_file.h"

#include <vector>

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

struct WindowedSincOptions {
  int iterations = 20;      // N, the Chebyshev order (Laplacian applications), 0..1000; 0: unchanged
  double pass_band = 0.01;  // kPB, 0 < kPB < 2
};

// Smooths mesh.vertices in place by the windowed-sinc filter above; triangles are unchanged. Vertices
// on a border (an edge with one triangle) or used by no triangle keep their positions. Then
// recomputes mesh.normals as for taubin_smooth(); the lattice tie is left as it was (call
// tie_surface_to_lattice()).
//
// mesh  #V x 3 LPS mm vertices, #F x 3 triangles
// Throws InputError("--smooth", ...) for parameters out of range. Jacobi updates gathered over each
// one-ring: the result is identical for any thread count. Parallel (OpenMP).
void windowed_sinc_smooth(SurfaceMesh& mesh, const WindowedSincOptions& options = {});

// The filter's Chebyshev coefficients c_0..c_N (N + 1 values, summing to 1), and its response
// f(k) = sum_i c_i T_i(1 - k/2) at Laplacian eigenvalue k in [0, 2].
std::vector<double> windowed_sinc_coefficients(const WindowedSincOptions& options);
double windowed_sinc_response(const std::vector<double>& coefficients, double k);

// Enclosed volume of a closed, outward-oriented surface by the divergence theorem (sum over
// triangles of a . (b x c) / 6, about the vertices' bounding-box centre, in double), mm^3.
double enclosed_volume_mm3(const SurfaceMesh& mesh);

// True when every edge is shared by exactly two triangles that use it in opposite directions (a
// closed, consistently oriented surface: one whose enclosed volume is defined).
bool is_closed_oriented_surface(const SurfaceMesh& mesh);

// Moves every vertex by the same distance t (mm, positive outward) along its unit vertex normal
// (recomputed first, angle-weighted, from the triangles) so that the enclosed volume equals
// target_mm3. The volume of the offset surface is a cubic polynomial in t, built exactly from the
// triangles and solved by Newton steps from t = 0; after rounding the vertices to float32 the volume
// is target_mm3 within 1e-6 relative (one more Newton step on the rounded vertices when it is not).
// Then recomputes mesh.normals. Returns t.
//
// mesh        a closed, consistently oriented surface (is_closed_oriented_surface), #V x 3 LPS mm
// target_mm3  > 0
// Throws InputError("mesh", ...) for an open surface or a target that is not positive, RuntimeError when
// Newton's method fails to reach 1e-12 relative in 50 steps. Deterministic (serial sums).
double restore_enclosed_volume(SurfaceMesh& mesh, double target_mm3);

// Angle-weighted vertex normals of a triangle mesh (Thurmer & Wuthrich 1998): unit, #V x 3; a vertex
// in no non-degenerate triangle keeps its previous normal (or gets (0, 0, 0) when there was none).
void recompute_vertex_normals(SurfaceMesh& mesh);

}  // namespace ctsurg
