// Centerlines built in memory for the vessel tests: a straight vessel, a circular arc, a helix and a
// Y bifurcation, with their analytic axes.
#pragma once

#include "ctsurg/core/centerline_file.h"

#include <cmath>
#include <functional>
#include <numbers>
#include <vector>

namespace ctsurg::sim::test {

// One branch through the points axis(s) for s = 0, ..., n - 1 with radius r (LPS mm).
inline Centerline branch_centerline(int n, double r, const std::function<std::array<double, 3>(double)>& axis) {
  Centerline c;
  for (int i = 0; i < n; ++i) {
    const auto p = axis(i);
    c.points.insert(c.points.end(), p.begin(), p.end());
    c.radius.push_back(r);
  }
  c.branch_offsets = {0, n};
  c.branch_nodes = {0, 1};
  c.nodes.insert(c.nodes.end(), c.points.begin(), c.points.begin() + 3);
  c.nodes.insert(c.nodes.end(), c.points.end() - 3, c.points.end());
  return c;
}

// n atoms h mm apart along +x from `start`.
inline Centerline straight_centerline(int n, double h, double r, std::array<double, 3> start = {0, 0, 0}) {
  return branch_centerline(n, r, [=](double s) { return std::array<double, 3>{start[0] + s * h, start[1], start[2]}; });
}

// A circle of radius R about the y axis through the origin, in the xz plane, from the +x side over
// `degrees` (passing the direction +z at 90 degrees from the start), n points.
inline Centerline arc_centerline(int n, double big_r, double degrees, double r) {
  const double step = degrees / (n - 1) * std::numbers::pi / 180;
  return branch_centerline(n, r, [=](double s) {
    return std::array<double, 3>{big_r * std::cos(s * step), 0, big_r * std::sin(s * step)};
  });
}

// A Y: a trunk of n atoms along +x from the origin to the junction, and two branches of n atoms at
// +-angle degrees from it in the xy plane, all h mm apart.
inline Centerline y_centerline(int n, double h, double angle_deg, double r) {
  Centerline c;
  const double a = angle_deg * std::numbers::pi / 180, j = (n - 1) * h;
  c.nodes = {0, 0, 0, j, 0, 0, j + (n - 1) * h * std::cos(a), (n - 1) * h * std::sin(a), 0,
             j + (n - 1) * h * std::cos(a), -(n - 1) * h * std::sin(a), 0};
  c.branch_offsets = {0};
  const auto branch = [&](std::array<double, 3> from, std::array<double, 3> d, int start, int end) {
    for (int i = 0; i < n; ++i) {
      for (int k = 0; k < 3; ++k) c.points.push_back(from[static_cast<size_t>(k)] + i * h * d[static_cast<size_t>(k)]);
      c.radius.push_back(r);
    }
    c.branch_offsets.push_back(static_cast<int64_t>(c.radius.size()));
    c.branch_nodes.push_back(start);
    c.branch_nodes.push_back(end);
  };
  branch({0, 0, 0}, {1, 0, 0}, 0, 1);
  branch({j, 0, 0}, {std::cos(a), std::sin(a), 0}, 1, 2);
  branch({j, 0, 0}, {std::cos(a), -std::sin(a), 0}, 1, 3);
  return c;
}

}  // namespace ctsurg::sim::test
