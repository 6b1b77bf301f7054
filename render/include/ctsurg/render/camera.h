// Cameras that frame an organ from named anatomical views.
//
// World frame: LPS millimetres, x towards the patient's Left, y Posterior, z Superior.
//   anterior   looks from -y towards +y, +z up (the patient's left on the picture's right)
//   posterior  looks from +y towards -y, +z up
//   left       looks from +x towards -x, +z up (posterior on the right)
//   right      looks from -x towards +x, +z up (anterior on the right)
//   superior   looks from +z down towards -z, anterior (-y) up (the patient's right on the right)
//   inferior   looks from -z up towards +z, anterior (-y) up (the patient's left on the right, as an
//              axial CT slice in the radiological convention)
//   AZ,EL      azimuth about +z from anterior (90 = left, 180 = posterior, 270 = right) and elevation
//              towards superior, degrees; the camera sits at centre + d (sin az cos el, -cos az cos el,
//              sin el) with up = (-sin az sin el, cos az sin el, cos el), so 0,0 is anterior.
// Framing: the camera looks at the centre of a bounding sphere and is placed so that the whole sphere
// (times a margin) fits the smaller side of the picture, in both projections.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <string>

namespace ctsurg {

enum class Projection { perspective, orthographic };

struct ViewDirection {
  std::string name;              // "anterior", ..., or "az30_el20"
  Eigen::Vector3d towards_eye;   // unit, from the organ's centre to the camera (LPS)
  Eigen::Vector3d up;            // unit, orthogonal to towards_eye: the picture's up (LPS)
};

// "anterior", "posterior", "left", "right", "superior", "inferior" or "AZ,EL" (degrees).
// InputError(option, "", ...) otherwise; `option` names the option in the message.
ViewDirection parse_view(const std::string& spec, const std::string& option = "--view");
// The view at azimuth and elevation (degrees), as described above.
ViewDirection view_from_angles(double azimuth_deg, double elevation_deg);

struct BoundingSphere {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // LPS mm
  double radius = 0.0;                               // mm
};
// The sphere around the axis-aligned box of `n` points (`xyz` n x 3, LPS mm), grown to hold
// `other` too when its radius is positive. Deterministic (no random start).
BoundingSphere bounding_sphere(const float* xyz, int64_t n, const BoundingSphere& other = {});

struct Camera {
  Eigen::Matrix4f view = Eigen::Matrix4f::Identity();        // LPS mm -> eye (OpenGL: looks along -z)
  Eigen::Matrix4f projection = Eigen::Matrix4f::Identity();  // eye -> clip
  Eigen::Vector3d eye = Eigen::Vector3d::Zero();              // camera position, LPS mm (orthographic: far back)
  Eigen::Vector3d forward = Eigen::Vector3d::UnitY();         // unit viewing direction, LPS
  Projection projection_kind = Projection::perspective;
  double mm_per_pixel_at_centre = 0.0;                        // at the sphere's centre
};

// A camera looking at `sphere` from `view`, the sphere (radius x `margin`) filling the smaller side
// of a `width` x `height` picture. Perspective: 30 degree field of view on the smaller side.
Camera frame_camera(const BoundingSphere& sphere, const ViewDirection& view, Projection projection, int width, int height,
                    double margin = 1.08);

}  // namespace ctsurg
