#include "ctsurg/sim/base/rigid_pose.h"

#include "ctsurg/core/error.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ctsurg::sim {
namespace {

std::array<double, 3> rotate(const Quaternion& q, const std::array<double, 3>& p) {
  const auto r = rotation_matrix(q);
  return {r[0] * p[0] + r[1] * p[1] + r[2] * p[2], r[3] * p[0] + r[4] * p[1] + r[5] * p[2], r[6] * p[0] + r[7] * p[1] + r[8] * p[2]};
}

TEST(RigidPose, AxisAngleRotatesRightHanded) {
  const Quaternion q = axis_angle_rotation({0, 0, 2}, 90, "test", "rotation");
  const auto p = rotate(q, {1, 0, 0});  // x -> y about +z
  EXPECT_NEAR(p[0], 0, 1e-12);
  EXPECT_NEAR(p[1], 1, 1e-12);
  EXPECT_NEAR(p[2], 0, 1e-12);
  EXPECT_NEAR(rotation_angle_deg(q), 90, 1e-9);
  // The matrix is a proper rotation: orthonormal with determinant 1.
  const auto r = rotation_matrix(axis_angle_rotation({1, -2, 0.5}, 137, "test", "rotation"));
  const double det = r[0] * (r[4] * r[8] - r[5] * r[7]) - r[1] * (r[3] * r[8] - r[5] * r[6]) + r[2] * (r[3] * r[7] - r[4] * r[6]);
  EXPECT_NEAR(det, 1, 1e-12);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double d = 0;
      for (int k = 0; k < 3; ++k) d += r[3 * i + k] * r[3 * j + k];
      EXPECT_NEAR(d, i == j ? 1 : 0, 1e-12);
    }
}

TEST(RigidPose, SlerpTurnsAtConstantSpeedAlongTheShorterArc) {
  const Quaternion a = kIdentityRotation, b = axis_angle_rotation({0, 1, 0}, 120, "test", "rotation");
  for (double s : {0.0, 0.25, 0.5, 0.75, 1.0}) {
    const Quaternion q = slerp(a, b, s);
    EXPECT_NEAR(rotation_angle_deg(q), 120 * s, 1e-9) << s;
    const auto p = rotate(q, {0, 0, 1});  // stays in the xz plane, turning about y
    EXPECT_NEAR(p[1], 0, 1e-12);
    EXPECT_NEAR(std::atan2(p[0], p[2]) * 180 / M_PI, 120 * s, 1e-9);
  }
  // -b is the same rotation: slerp takes the 120 degree arc, not the 240 degree one.
  const Quaternion nb{-b[0], -b[1], -b[2], -b[3]};
  EXPECT_NEAR(rotation_angle_deg(slerp(a, nb, 0.5)), 60, 1e-9);
  // Multiplication composes: two 45 degree turns about z are one of 90.
  const Quaternion h = axis_angle_rotation({0, 0, 1}, 45, "test", "rotation");
  EXPECT_NEAR(rotation_angle_deg(multiply(h, h)), 90, 1e-9);
}

TEST(RigidPose, KeysThatAreNotRotationsAreRefused) {
  EXPECT_THROW(checked_rotation({2, 0, 0, 0}, "scenario.yaml", "tools[0].path[1].quaternion"), InputError);
  EXPECT_THROW(checked_rotation({0, 0, 0, 0}, "scenario.yaml", "q"), InputError);
  EXPECT_THROW(checked_rotation({NAN, 0, 0, 1}, "scenario.yaml", "q"), InputError);
  EXPECT_THROW(axis_angle_rotation({0, 0, 0}, 30, "scenario.yaml", "rotation"), InputError);
  EXPECT_THROW(axis_angle_rotation({0, 0, 1}, INFINITY, "scenario.yaml", "rotation"), InputError);
  try {
    checked_rotation({1, 1, 0, 0}, "scenario.yaml", "tools[0].path[1].quaternion");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("tools[0].path[1].quaternion"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("not a rotation"), std::string::npos) << e.what();
  }
  const Quaternion q = checked_rotation({1.0004, 0, 0, 0}, "s", "q");  // rounding in a file: normalised
  EXPECT_DOUBLE_EQ(q[0], 1);
}

}  // namespace
}  // namespace ctsurg::sim
