// Tests for mesh/include/ctsurg/mesh/surface_smoothing.h: Taubin smoothing removes the partial-volume
// wobble of a CT sphere (area error falls) while the volume stays within 1 % (the point of
// mu < -lambda); normals stay unit and outward; bad parameters throw.
#include "ctsurg/mesh/surface_smoothing.h"

#include "ctsurg/core/error.h"
#include "ctsurg/mesh/marching_cubes.h"
#include "ctsurg/preprocess/synthetic_phantom.h"
#include "surface_checks.h"

#include <gtest/gtest.h>

#include <cmath>

namespace {

struct Sphere {
  ctsurg::PhantomShape shape;
  ctsurg::SurfaceMesh mesh;
};

Sphere ct_sphere() {
  Sphere s;
  s.shape.radius_mm = 15.0;
  s.shape.centre_mm = {0.4, -0.3, 0.2};
  ctsurg::PhantomRasterOptions o;
  o.spacing_mm = {1.0, 1.0, 1.0};
  o.supersample = 3;
  s.mesh = ctsurg::marching_cubes(ctsurg::rasterise_phantom(s.shape, o, "test").hu, -470.0);
  return s;
}

TEST(SurfaceSmoothing, TaubinKeepsVolumeAndRemovesTheWobble) {
  const Sphere s = ct_sphere();
  const double V = ctsurg::phantom_volume_mm3(s.shape), A = ctsurg::phantom_area_mm2(s.shape);
  const double ea0 = ctsurg::test::surface_area(s.mesh) / A - 1.0;

  ctsurg::SurfaceMesh taubin = s.mesh;
  ctsurg::taubin_smooth(taubin, {20});
  const double ev = ctsurg::test::enclosed_volume(taubin) / V - 1.0, ea = ctsurg::test::surface_area(taubin) / A - 1.0;
  EXPECT_EQ(ctsurg::test::manifold_problem(taubin), "");
  EXPECT_LT(std::abs(ev), 0.01) << "Taubin changed the volume by " << ev;
  EXPECT_LT(std::abs(ea), std::abs(ea0)) << "area error before " << ea0 << ", after " << ea;

  double worst = 1.0;
  for (int64_t v = 0; v < taubin.vertex_count(); ++v) {
    const auto i = static_cast<std::size_t>(v);
    const Eigen::Vector3d n(taubin.normals[3 * i], taubin.normals[3 * i + 1], taubin.normals[3 * i + 2]);
    ASSERT_NEAR(n.norm(), 1.0, 1e-5);
    worst = std::min(worst, n.dot((ctsurg::test::vertex(taubin, static_cast<uint32_t>(v)) - s.shape.centre_mm).normalized()));
  }
  EXPECT_GT(worst, 0.98);
}

TEST(SurfaceSmoothing, ZeroIterationsIsIdentityAndBadParametersThrow) {
  const Sphere s = ct_sphere();
  ctsurg::SurfaceMesh m = s.mesh;
  ctsurg::taubin_smooth(m, {0});
  EXPECT_EQ(m.vertices, s.mesh.vertices);
  EXPECT_THROW(ctsurg::taubin_smooth(m, {-1}), ctsurg::InputError);
  EXPECT_THROW(ctsurg::taubin_smooth(m, {5, 1.5}), ctsurg::InputError);
  EXPECT_THROW(ctsurg::taubin_smooth(m, {5, 0.5, 2.5}), ctsurg::InputError);
}

}  // namespace
