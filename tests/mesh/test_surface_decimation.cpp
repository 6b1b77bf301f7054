// Tests for mesh/include/ctsurg/mesh/surface_decimation.h: quadric decimation reaches the target,
// keeps a closed oriented manifold of the same topology (sphere and torus), stays close to the
// original shape and volume, and is deterministic.
#include "ctsurg/mesh/surface_decimation.h"

#include "ctsurg/core/error.h"
#include "ctsurg/mesh/marching_cubes.h"
#include "ctsurg/preprocess/synthetic_phantom.h"
#include "surface_checks.h"

#include <gtest/gtest.h>

#include <cmath>

namespace {

ctsurg::SurfaceMesh implicit_surface(const ctsurg::PhantomShape& s, double h) {
  ctsurg::PhantomRasterOptions o;
  o.spacing_mm = Eigen::Vector3d::Constant(h);
  o.margin_mm = 2.0 * h;
  ctsurg::Volume<float> f(ctsurg::phantom_geometry(s, o, "test"));
  const auto& g = f.geometry;
  for (int64_t k = 0; k < g.dims[2]; ++k)
    for (int64_t j = 0; j < g.dims[1]; ++j)
      for (int64_t i = 0; i < g.dims[0]; ++i)
        f(i, j, k) = float(-ctsurg::phantom_implicit_mm(s, g.index_to_world(Eigen::Vector3d(double(i), double(j), double(k)))));
  return ctsurg::marching_cubes(f, 0.0);
}

TEST(SurfaceDecimation, KeepsTopologyShapeAndVolume) {
  for (const auto kind : {ctsurg::PhantomKind::Sphere, ctsurg::PhantomKind::Torus}) {
    ctsurg::PhantomShape s;
    s.kind = kind;
    const ctsurg::SurfaceMesh full = implicit_surface(s, 1.0);
    ctsurg::SurfaceMesh m = full;
    const int64_t target = full.triangle_count() / 8;
    ctsurg::decimate_surface(m, target);
    SCOPED_TRACE(ctsurg::phantom_kind_name(kind));
    EXPECT_LE(m.triangle_count(), target + 2);
    EXPECT_GT(m.triangle_count(), target * 9 / 10);
    ASSERT_EQ(ctsurg::test::manifold_problem(m), "");
    EXPECT_EQ(ctsurg::test::euler_characteristic(m), ctsurg::test::euler_characteristic(full));
    EXPECT_NEAR(ctsurg::test::enclosed_volume(m) / ctsurg::test::enclosed_volume(full), 1.0, 0.01);
    double worst = 0.0;
    for (int64_t v = 0; v < m.vertex_count(); ++v) {
      worst = std::max(worst, std::abs(ctsurg::phantom_implicit_mm(s, ctsurg::test::vertex(m, static_cast<uint32_t>(v)))));
    }
    EXPECT_LT(worst, 0.25) << "a decimated vertex left the surface by " << worst << " mm";
    EXPECT_TRUE(m.grid_weights.empty());
    EXPECT_EQ(m.normals.size(), m.vertices.size());
    ctsurg::SurfaceMesh again = full;
    ctsurg::decimate_surface(again, target);
    EXPECT_EQ(again.vertices, m.vertices);
    EXPECT_EQ(again.triangles, m.triangles);
  }
}

TEST(SurfaceDecimation, TargetAboveCountIsIdentityAndTinyTargetThrows) {
  ctsurg::PhantomShape s;
  const ctsurg::SurfaceMesh full = implicit_surface(s, 2.0);
  ctsurg::SurfaceMesh m = full;
  ctsurg::decimate_surface(m, full.triangle_count());
  EXPECT_EQ(m.vertices, full.vertices);
  EXPECT_THROW(ctsurg::decimate_surface(m, 3), ctsurg::InputError);
}

}  // namespace
