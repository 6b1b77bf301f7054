// Properties of triangle surfaces shared by the mesh tests: closed oriented 2-manifold, enclosed
// volume and area, Euler characteristic.
#pragma once

#include "ctsurg/core/surface_mesh_file.h"

#include <Eigen/Core>

#include <cstdint>
#include <string>

namespace ctsurg::test {

// Vertex v of `m` (LPS mm).
Eigen::Vector3d vertex(const SurfaceMesh& m, uint32_t v);
// Every edge is used by exactly two triangles, once in each direction; no triangle repeats a
// vertex. Returns an empty string or the first problem.
std::string manifold_problem(const SurfaceMesh& m);
// Enclosed volume by the divergence theorem, mm^3 (positive for outward orientation).
double enclosed_volume(const SurfaceMesh& m);
// Total triangle area, mm^2.
double surface_area(const SurfaceMesh& m);
// V - E + F over the vertices used by triangles (2 for a sphere, 0 for a torus).
int64_t euler_characteristic(const SurfaceMesh& m);

}  // namespace ctsurg::test
