#include "ctsurg/sim/base/rigid_pose.h"

#include "ctsurg/core/error.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace ctsurg::sim {

Quaternion checked_rotation(const Quaternion& q, const std::string& where, const std::string& field) {
  double n2 = 0;
  for (const double c : q) {
    if (!std::isfinite(c)) throw InputError(where, field, "a quaternion component is not finite");
    n2 += c * c;
  }
  const double n = std::sqrt(n2);
  if (std::abs(n - 1) > 1e-3) {
    throw InputError(where, field, "is not a rotation: a unit quaternion [w, x, y, z] has norm 1, this one " + std::to_string(n));
  }
  return {q[0] / n, q[1] / n, q[2] / n, q[3] / n};
}

Quaternion axis_angle_rotation(const std::array<double, 3>& axis, double angle_deg, const std::string& where,
                               const std::string& field) {
  if (!std::isfinite(angle_deg)) throw InputError(where, field + ".angle_deg", "must be finite");
  double n2 = 0;
  for (const double c : axis) {
    if (!std::isfinite(c)) throw InputError(where, field + ".axis", "a component is not finite");
    n2 += c * c;
  }
  if (!(n2 > 1e-24)) throw InputError(where, field + ".axis", "must not be zero");
  const double n = std::sqrt(n2), half = angle_deg * std::numbers::pi / 360.0, s = std::sin(half) / n;
  return {std::cos(half), axis[0] * s, axis[1] * s, axis[2] * s};
}

Quaternion multiply(const Quaternion& a, const Quaternion& b) {
  return {a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3], a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
          a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1], a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]};
}

Quaternion slerp(const Quaternion& a, const Quaternion& b_in, double s) {
  Quaternion b = b_in;
  double d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
  if (d < 0) {  // q and -q are the same rotation: take the shorter arc
    for (double& c : b) c = -c;
    d = -d;
  }
  Quaternion r;
  if (d > 1 - 1e-12) {  // (nearly) the same rotation: the normalised linear blend is exact to rounding
    for (size_t i = 0; i < 4; ++i) r[i] = a[i] + s * (b[i] - a[i]);
  } else {
    const double theta = std::acos(std::clamp(d, -1.0, 1.0));
    const double wa = std::sin((1 - s) * theta) / std::sin(theta), wb = std::sin(s * theta) / std::sin(theta);
    for (size_t i = 0; i < 4; ++i) r[i] = wa * a[i] + wb * b[i];
  }
  const double n = std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2] + r[3] * r[3]);
  for (double& c : r) c /= n;
  return r;
}

std::array<double, 9> rotation_matrix(const Quaternion& q) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  return {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
          2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
          2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
}

double rotation_angle_deg(const Quaternion& q) {
  return 2 * std::acos(std::clamp(std::abs(q[0]), 0.0, 1.0)) * 180.0 / std::numbers::pi;
}

}  // namespace ctsurg::sim
