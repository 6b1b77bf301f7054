// The shapes the tools are made of (Mosegaard & Sorensen 2005, section 2.7): a sphere (the tip of a
// probe, the jaws of a grab, the region a point force acts on) and a triangle (the area a blade's edge
// sweeps between two times; a swept blade is two triangles per straight stretch of its path).
//
// Units: LPS mm (or a run's local frame: LPS minus its origin, particle_state.h).
#pragma once

#include <array>

namespace ctsurg::sim {

struct Sphere {
  std::array<double, 3> centre{0, 0, 0};  // mm
  double radius = 0;                       // mm, > 0
};

struct Triangle {
  std::array<double, 3> a{}, b{}, c{};  // mm
};

// The quad that a blade's edge (a segment of vector `edge` mm centred on the blade's path) sweeps when
// its centre moves in a straight line from c0 to c1, as two triangles: {a0, b0, b1} and {a0, b1, a1},
// a = centre - edge / 2, b = centre + edge / 2.
inline std::array<Triangle, 2> swept_blade(const std::array<double, 3>& c0, const std::array<double, 3>& c1,
                                           const std::array<double, 3>& edge) {
  const std::array<double, 3> a0{c0[0] - edge[0] / 2, c0[1] - edge[1] / 2, c0[2] - edge[2] / 2};
  const std::array<double, 3> b0{c0[0] + edge[0] / 2, c0[1] + edge[1] / 2, c0[2] + edge[2] / 2};
  const std::array<double, 3> a1{c1[0] - edge[0] / 2, c1[1] - edge[1] / 2, c1[2] - edge[2] / 2};
  const std::array<double, 3> b1{c1[0] + edge[0] / 2, c1[1] + edge[1] / 2, c1[2] + edge[2] / 2};
  return {Triangle{a0, b0, b1}, Triangle{a0, b1, a1}};
}

}  // namespace ctsurg::sim
