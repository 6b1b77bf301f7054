// A rigid body's pose: a rotation (unit quaternion) and a translation, and how a pose is interpolated
// between two keyframes (an instrument's path, scenario/tool_timeline.h).
//
// Quaternions are {w, x, y, z} (Hamilton convention, w the scalar part); a pose maps a point q of the
// body's own frame to R(quaternion) q + translation in the run's frame. Rotations are interpolated by
// slerp along the shorter arc (Shoemake 1985, "Animating rotation with quaternion curves"): constant
// angular speed between keys, whatever the angle; a linear blend of matrices would shear the body.
//
// Units: translation mm, angles degrees where a function says so.
#pragma once

#include <array>
#include <string>

namespace ctsurg::sim {

using Quaternion = std::array<double, 4>;  // {w, x, y, z}

inline constexpr Quaternion kIdentityRotation{1, 0, 0, 0};

// The unit quaternion of `q`: InputError(where, field, ...) unless q is finite and its norm is within
// 1e-3 of 1 (a key that is not a rotation is a mistake to report, not a quaternion to scale quietly).
Quaternion checked_rotation(const Quaternion& q, const std::string& where, const std::string& field);
// The rotation by `angle_deg` degrees about `axis` (right-handed; any non-zero length): InputError
// naming where/field when the axis is zero or a value is not finite.
Quaternion axis_angle_rotation(const std::array<double, 3>& axis, double angle_deg, const std::string& where,
                               const std::string& field);

// The rotation a * b: b first, then a.
Quaternion multiply(const Quaternion& a, const Quaternion& b);
// Slerp from a (s = 0) to b (s = 1) along the shorter arc; unit inputs.
Quaternion slerp(const Quaternion& a, const Quaternion& b, double s);
// The row-major 3 x 3 rotation matrix of a unit quaternion.
std::array<double, 9> rotation_matrix(const Quaternion& q);
// The rotation angle of a unit quaternion, degrees in [0, 180].
double rotation_angle_deg(const Quaternion& q);

}  // namespace ctsurg::sim
