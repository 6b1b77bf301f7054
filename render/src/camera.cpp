#include "ctsurg/render/camera.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "ctsurg/core/error.h"

namespace ctsurg {

namespace {

constexpr double kPerspectiveFovDeg = 30.0;

ViewDirection named(const std::string& name, Eigen::Vector3d towards_eye, Eigen::Vector3d up) {
  return {name, towards_eye, up};
}

}  // namespace

ViewDirection view_from_angles(double azimuth_deg, double elevation_deg) {
  const double az = azimuth_deg * std::numbers::pi / 180.0, el = elevation_deg * std::numbers::pi / 180.0;
  ViewDirection v;
  std::ostringstream name;
  name << "az" << azimuth_deg << "_el" << elevation_deg;
  v.name = name.str();
  v.towards_eye = Eigen::Vector3d(std::sin(az) * std::cos(el), -std::cos(az) * std::cos(el), std::sin(el)).normalized();
  v.up = Eigen::Vector3d(-std::sin(az) * std::sin(el), std::cos(az) * std::sin(el), std::cos(el)).normalized();
  return v;
}

ViewDirection parse_view(const std::string& spec, const std::string& option) {
  using V = Eigen::Vector3d;
  if (spec == "anterior") return named(spec, V(0, -1, 0), V(0, 0, 1));
  if (spec == "posterior") return named(spec, V(0, 1, 0), V(0, 0, 1));
  if (spec == "left") return named(spec, V(1, 0, 0), V(0, 0, 1));
  if (spec == "right") return named(spec, V(-1, 0, 0), V(0, 0, 1));
  if (spec == "superior") return named(spec, V(0, 0, 1), V(0, -1, 0));
  if (spec == "inferior") return named(spec, V(0, 0, -1), V(0, -1, 0));
  const auto comma = spec.find(',');
  if (comma != std::string::npos) {
    try {
      std::size_t used_az = 0, used_el = 0;
      const std::string az_text = spec.substr(0, comma), el_text = spec.substr(comma + 1);
      const double az = std::stod(az_text, &used_az), el = std::stod(el_text, &used_el);
      if (used_az == az_text.size() && used_el == el_text.size() && std::isfinite(az) && el >= -90.0 && el <= 90.0)
        return view_from_angles(az, el);
    } catch (const std::exception&) {
    }
  }
  throw InputError(option, "", "'" + spec +
                                   "' is not a view: use anterior, posterior, left, right, superior, inferior or "
                                   "AZIMUTH,ELEVATION in degrees (elevation in [-90, 90])");
}

BoundingSphere bounding_sphere(const float* xyz, int64_t n, const BoundingSphere& other) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (int64_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], double(xyz[3 * i + c])), hi[c] = std::max(hi[c], double(xyz[3 * i + c]));
  if (other.radius > 0.0) {
    lo = lo.cwiseMin(other.centre - Eigen::Vector3d::Constant(other.radius));
    hi = hi.cwiseMax(other.centre + Eigen::Vector3d::Constant(other.radius));
  }
  BoundingSphere s;
  if (!(lo.array() <= hi.array()).all()) return s;
  s.centre = 0.5 * (lo + hi);
  double r2 = 0.0;
  for (int64_t i = 0; i < n; ++i) {
    const Eigen::Vector3d p(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    r2 = std::max(r2, (p - s.centre).squaredNorm());
  }
  s.radius = std::sqrt(r2);
  if (other.radius > 0.0) s.radius = std::max(s.radius, (other.centre - s.centre).norm() + other.radius);
  s.radius = std::max(s.radius, 1e-3);
  return s;
}

Camera frame_camera(const BoundingSphere& sphere, const ViewDirection& view, Projection projection, int width, int height,
                    double margin) {
  Camera cam;
  cam.projection_kind = projection;
  const double r = std::max(sphere.radius, 1e-3) * margin;
  const double aspect = double(width) / double(height);
  const double half_fov = 0.5 * kPerspectiveFovDeg * std::numbers::pi / 180.0;
  // Distance at which the sphere just fits the smaller side of the perspective frustum.
  const double distance = projection == Projection::perspective ? r / std::sin(half_fov) : 4.0 * r;
  const Eigen::Vector3d forward = -view.towards_eye.normalized();
  const Eigen::Vector3d right = forward.cross(view.up).normalized();
  const Eigen::Vector3d up = right.cross(forward);
  cam.eye = sphere.centre + distance * view.towards_eye.normalized();
  cam.forward = forward;

  Eigen::Matrix4d v = Eigen::Matrix4d::Identity();
  v.block<1, 3>(0, 0) = right.transpose();
  v.block<1, 3>(1, 0) = up.transpose();
  v.block<1, 3>(2, 0) = -forward.transpose();
  v(0, 3) = -right.dot(cam.eye);
  v(1, 3) = -up.dot(cam.eye);
  v(2, 3) = forward.dot(cam.eye);
  cam.view = v.cast<float>();

  const double near_plane = std::max(distance - 1.5 * r, 1e-3 * r), far_plane = distance + 1.5 * r;
  // Half extents at unit distance (perspective) or in mm (orthographic) on the smaller side.
  Eigen::Matrix4d p = Eigen::Matrix4d::Zero();
  if (projection == Projection::perspective) {
    const double t = std::tan(half_fov);
    const double sx = aspect >= 1.0 ? t * aspect : t, sy = aspect >= 1.0 ? t : t / aspect;
    p(0, 0) = 1.0 / sx;
    p(1, 1) = 1.0 / sy;
    p(2, 2) = -(far_plane + near_plane) / (far_plane - near_plane);
    p(2, 3) = -2.0 * far_plane * near_plane / (far_plane - near_plane);
    p(3, 2) = -1.0;
    cam.mm_per_pixel_at_centre = 2.0 * distance * sy / height;
  } else {
    const double sx = aspect >= 1.0 ? r * aspect : r, sy = aspect >= 1.0 ? r : r / aspect;
    p(0, 0) = 1.0 / sx;
    p(1, 1) = 1.0 / sy;
    p(2, 2) = -2.0 / (far_plane - near_plane);
    p(2, 3) = -(far_plane + near_plane) / (far_plane - near_plane);
    p(3, 3) = 1.0;
    cam.mm_per_pixel_at_centre = 2.0 * sy / height;
  }
  cam.projection = p.cast<float>();
  return cam;
}

}  // namespace ctsurg
