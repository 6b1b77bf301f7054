// The signed distance to a closed triangle mesh, sampled on a regular grid of the mesh's own frame:
// how a rigid instrument knows, in constant time per point, whether a point of the tissue is inside
// it, how deep, and which way is out (instrument.h; the per-point query is
// kernels/instrument_contact_impl.h, for the CPU and CUDA).
//
// Baked once per instrument (it is rigid): exact point-triangle distances in a band of two cells
// around every triangle, carried to the rest of the grid by fast sweeping with the closest triangle
// (Bridson's makelevelset3, after Tsai 2002: every node's value is the exact distance to a triangle;
// within two cells of the surface to the closest one, deeper to a nearby one the sweep carried, within
// a few percent of the depth: contact needs the depth and the way out, both exact near the surface, and
// a direction deeper in); the sign from the parity of crossings of grid rows with the
// surface, along x, y and z, by majority (a row grazing an edge or a vertex miscounts on one axis, not
// on three). Rows are offset by an irrational fraction of a cell so that meshes built on round numbers
// do not put edges exactly on them.
//
// Units: mm. Values: negative inside, positive outside. Layout: x fastest.
#pragma once

#include "ctsurg/core/triangle_mesh_file.h"

#include <array>
#include <cstdint>
#include <vector>

namespace ctsurg::sim {

struct SignedDistanceGrid {
  std::array<double, 3> origin{0, 0, 0};  // the first node, mm (the mesh's frame)
  double spacing = 0;                     // mm, the same on every axis
  std::array<int32_t, 3> dims{0, 0, 0};   // nodes per axis
  std::vector<float> phi;                 // dims[0] * dims[1] * dims[2] values, mm, x fastest
};

// The grid over the mesh's bounding box grown by `margin_cells` cells on every side, with `spacing`
// mm between nodes. mesh: a closed, consistently oriented triangle mesh (instrument.h checks it);
// spacing > 0; the caller bounds the node count.
SignedDistanceGrid bake_signed_distance_grid(const TriangleMesh& mesh, double spacing, int margin_cells = 3);

// The distance from p to triangle (a, b, c), mm (Ericson, Real-Time Collision Detection, 5.1.5).
double point_triangle_distance(const std::array<double, 3>& p, const double* a, const double* b, const double* c);

}  // namespace ctsurg::sim
