// Decimation of a closed triangle surface by quadric-error edge collapse (M. Garland & P. Heckbert,
// "Surface simplification using quadric error metrics", SIGGRAPH 1997), through CGAL's
// Surface_mesh_simplification (confined to surface_decimation.cpp): each collapse puts the merged
// vertex where the sum of squared distances to the planes of the original triangles around it is
// least; collapses that would flip a triangle's normal are refused (Bounded_normal_change_filter),
// and the link condition keeps the mesh a 2-manifold of the same topology.
#pragma once

#include "ctsurg/core/surface_mesh_file.h"

#include <cstdint>

namespace ctsurg {

// Decimates `mesh` in place to at most about `target_triangles` triangles (the collapse stops at the
// first edge count under 3/2 x target, the count of a closed mesh with that many triangles, or
// earlier when no collapse is allowed). Vertex normals are recomputed (angle-weighted); the lattice
// tie arrays are cleared: call tie_surface_to_lattice() (lattice_tie.h) afterwards.
//
// mesh              #V x 3 LPS mm vertices, #F x 3 triangles, counter-clockwise from outside
// target_triangles  >= 4; a target at or above #F leaves the mesh as it is
// Throws InputError("--decimate", ...) for a target below 4 and RuntimeError when the mesh cannot be
// built as a polygon mesh. Deterministic (same input, same output).
void decimate_surface(SurfaceMesh& mesh, int64_t target_triangles);

}  // namespace ctsurg
