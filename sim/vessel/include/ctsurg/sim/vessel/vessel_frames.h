// Frames along a polyline, for a tube's rings and the chain's rest orientations:
//
//   tangents   t_i = C_{i-1}C_{i+1} / |C_{i-1}C_{i+1}| (one-sided at the ends): the axis of the
//              paper's eq. 15-16 (Huang et al. 2006, section 5.1)
//   plane spoke  eq. 15: the first spoke of atom i, perpendicular to t_i and in the plane xOy
//              (z = 0), as the paper chooses it; it flips by up to 180 degrees between neighbours
//              where the tangent passes near z (a twist artefact: vessel_skinning.h measures it)
//   rotation-minimising normals  Wang, Juettler, Zheng & Liu 2008, "Computation of rotation minimizing
//              frames" (ACM TOG 27(1)), the double reflection method: u_{i+1} is u_i reflected in the
//              bisector plane of C_i C_{i+1}, then in the plane that takes the reflected tangent onto
//              t_{i+1}; fourth-order accurate, no trigonometry, no flips.
//
// Units: mm (any frame, usually the run's local one); directions unit vectors.
#pragma once

#include "ctsurg/sim/base/simulation_engine.h"

#include <cstddef>

namespace ctsurg::sim {

// Unit tangents (n x 3) of the polyline `points` (n x 3, n >= 2, consecutive points distinct).
void polyline_tangents(const double* points, size_t n, double* tangents);

// Eq. 15's first spoke for tangent t (unit): (-t_y, t_x, 0) normalised; the x axis when t is within
// 1e-9 of +-z (any direction of xOy is then perpendicular).
Vec3 plane_spoke(const Vec3& t);

// Rotation-minimising unit normals u (n x 3) along `points` (n x 3) with unit `tangents` (n x 3),
// u_0 = u0 made perpendicular to t_0 (u0 must not be parallel to t_0).
void rotation_minimizing_normals(const double* points, const double* tangents, size_t n, const Vec3& u0, double* normals);

}  // namespace ctsurg::sim
