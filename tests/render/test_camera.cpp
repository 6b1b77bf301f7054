// Named views in the LPS frame and automatic framing (camera.h).
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "ctsurg/core/error.h"
#include "ctsurg/render/camera.h"

namespace {

// Where a world point lands in normalised device coordinates.
Eigen::Vector3d ndc(const ctsurg::Camera& c, const Eigen::Vector3d& p) {
  const Eigen::Vector4f clip = c.projection * c.view * Eigen::Vector4f(float(p.x()), float(p.y()), float(p.z()), 1.0f);
  return Eigen::Vector3d(clip.x() / clip.w(), clip.y() / clip.w(), clip.z() / clip.w());
}

}  // namespace

TEST(Camera, NamedViewsLookFromTheRightSide) {
  const ctsurg::BoundingSphere s{Eigen::Vector3d(10, -5, 3), 20.0};
  struct Case {
    const char* view;
    Eigen::Vector3d right_of_picture, top_of_picture;
  };
  const Case cases[] = {
      {"anterior", {1, 0, 0}, {0, 0, 1}},  {"posterior", {-1, 0, 0}, {0, 0, 1}}, {"left", {0, 1, 0}, {0, 0, 1}},
      {"right", {0, -1, 0}, {0, 0, 1}},    {"superior", {-1, 0, 0}, {0, -1, 0}}, {"inferior", {1, 0, 0}, {0, -1, 0}},
  };
  for (const auto projection : {ctsurg::Projection::perspective, ctsurg::Projection::orthographic}) {
    for (const Case& c : cases) {
      const ctsurg::Camera cam = ctsurg::frame_camera(s, ctsurg::parse_view(c.view), projection, 200, 100);
      const Eigen::Vector3d centre = ndc(cam, s.centre);
      EXPECT_NEAR(centre.x(), 0.0, 1e-5) << c.view;
      EXPECT_NEAR(centre.y(), 0.0, 1e-5) << c.view;
      EXPECT_GT(ndc(cam, s.centre + 10.0 * c.right_of_picture).x(), 0.1) << c.view;
      EXPECT_GT(ndc(cam, s.centre + 10.0 * c.top_of_picture).y(), 0.1) << c.view;
      // The whole sphere is inside the picture and in front of the near plane.
      for (int k = 0; k < 3; ++k)
        for (const double sign : {-1.0, 1.0}) {
          const Eigen::Vector3d q = ndc(cam, s.centre + sign * s.radius * Eigen::Vector3d::Unit(k));
          EXPECT_LE(std::abs(q.x()), 1.0) << c.view;
          EXPECT_LE(std::abs(q.y()), 1.0) << c.view;
          EXPECT_LE(std::abs(q.z()), 1.0) << c.view;
        }
    }
  }
}

TEST(Camera, AnglesMatchNamedViews) {
  const auto same = [](const ctsurg::ViewDirection& a, const ctsurg::ViewDirection& b) {
    return (a.towards_eye - b.towards_eye).norm() < 1e-12 && (a.up - b.up).norm() < 1e-12;
  };
  EXPECT_TRUE(same(ctsurg::parse_view("0,0"), ctsurg::parse_view("anterior")));
  EXPECT_TRUE(same(ctsurg::parse_view("90,0"), ctsurg::parse_view("left")));
  EXPECT_TRUE(same(ctsurg::parse_view("180,0"), ctsurg::parse_view("posterior")));
  EXPECT_TRUE(same(ctsurg::parse_view("-90,0"), ctsurg::parse_view("right")));
  EXPECT_THROW(ctsurg::parse_view("front"), ctsurg::InputError);
  EXPECT_THROW(ctsurg::parse_view("10,95"), ctsurg::InputError);
  EXPECT_THROW(ctsurg::parse_view("10,x"), ctsurg::InputError);
}

TEST(Camera, BoundingSphereHoldsThePoints) {
  const float p[] = {0, 0, 0, 10, 0, 0, 0, 4, 0, 0, 0, -6};
  const ctsurg::BoundingSphere s = ctsurg::bounding_sphere(p, 4);
  for (int i = 0; i < 4; ++i) EXPECT_LE((Eigen::Vector3d(p[3 * i], p[3 * i + 1], p[3 * i + 2]) - s.centre).norm(), s.radius + 1e-9);
}
