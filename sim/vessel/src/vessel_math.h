// Eigen shorthands and conversions for the vessel model's sources (not public: the headers speak
// std::array, base/rigid_pose.h's Quaternion {w, x, y, z}).
#pragma once

#include "ctsurg/sim/base/rigid_pose.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cmath>
#include <cstddef>
#include <vector>

namespace ctsurg::sim {

using V3 = Eigen::Vector3d;
using M3 = Eigen::Matrix3d;
using Q = Eigen::Quaterniond;

// Item i of a flat array of 3-vectors (x0 y0 z0 x1 ...).
inline V3 at(const std::vector<double>& a, size_t i) { return {a[3 * i], a[3 * i + 1], a[3 * i + 2]}; }

inline Q to_eigen(const Quaternion& q) { return Q(q[0], q[1], q[2], q[3]); }
inline Quaternion to_quaternion(const Q& q) { return {q.w(), q.x(), q.y(), q.z()}; }

inline M3 skew(const V3& v) {
  M3 m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

// exp of a rotation vector (radians x axis) as a unit quaternion.
inline Q rotation_exp(const V3& w) {
  const double a = w.norm();
  if (a < 1e-12) return Q(1, 0.5 * w.x(), 0.5 * w.y(), 0.5 * w.z()).normalized();
  const V3 ax = w / a;
  return Q(Eigen::AngleAxisd(a, ax));
}

// The rotation vector of a unit quaternion (the shorter arc).
inline V3 rotation_log(Q q) {
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  const V3 v = q.vec();
  const double s = v.norm();
  if (s < 1e-12) return 2 * v;
  return 2 * std::atan2(s, q.w()) * v / s;
}

}  // namespace ctsurg::sim
