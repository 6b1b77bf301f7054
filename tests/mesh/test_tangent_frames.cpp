// Tangent frames: analytic tangents on a plane (both handedness) and a cylinder, and orthonormal
// frames with the atlas's handedness on a marching-cubes sphere.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "ctsurg/core/error.h"
#include "ctsurg/mesh/marching_cubes.h"
#include "ctsurg/mesh/tangent_frames.h"
#include "ctsurg/mesh/uv_atlas.h"

namespace {

using Vec3 = Eigen::Vector3d;

struct Grid {
  std::vector<float> vertices, normals, uvs;
  std::vector<uint32_t> triangles;
};

// An n x n grid of quads, two counter-clockwise triangles each (seen from +normal), positions and
// normals from `at(s, t)` for s, t in [0, 1].
template <class F>
Grid grid(int n, F at) {
  Grid g;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const auto [p, nrm, uv] = at(double(i) / n, double(j) / n);
      for (int c = 0; c < 3; ++c) g.vertices.push_back(float(p[c])), g.normals.push_back(float(nrm[c]));
      g.uvs.push_back(float(uv[0]));
      g.uvs.push_back(float(uv[1]));
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const uint32_t a = uint32_t(j * (n + 1) + i), b = a + 1, c = a + uint32_t(n + 1), d = c + 1;
      g.triangles.insert(g.triangles.end(), {a, b, d, a, d, c});
    }
  return g;
}

Vec3 tangent(const std::vector<float>& t, std::size_t v) { return Vec3(t[4 * v], t[4 * v + 1], t[4 * v + 2]); }

TEST(TangentFrames, PlaneGivesPlusXAndHandednessFromV) {
  // z = 0 plane, normal +z; u along +x. v down the image along -y: bitangent +y = N x T, w = +1.
  const auto down = grid(6, [](double s, double t) {
    return std::tuple{Vec3(10 * s, 7 * t, 0), Vec3(0, 0, 1), Eigen::Vector2d(0.1 + 0.5 * s, 0.9 - 0.5 * t)};
  });
  const auto td = ctsurg::tangent_frames(down.vertices, down.normals, down.triangles, down.uvs);
  for (std::size_t v = 0; v < down.vertices.size() / 3; ++v) {
    EXPECT_NEAR((tangent(td, v) - Vec3::UnitX()).norm(), 0.0, 1e-6);
    EXPECT_EQ(td[4 * v + 3], 1.0f);
  }
  // v growing along +y: the image is mirrored, w = -1.
  const auto up = grid(6, [](double s, double t) {
    return std::tuple{Vec3(10 * s, 7 * t, 0), Vec3(0, 0, 1), Eigen::Vector2d(0.1 + 0.5 * s, 0.1 + 0.5 * t)};
  });
  const auto tu = ctsurg::tangent_frames(up.vertices, up.normals, up.triangles, up.uvs);
  for (std::size_t v = 0; v < up.vertices.size() / 3; ++v) {
    EXPECT_NEAR((tangent(tu, v) - Vec3::UnitX()).norm(), 0.0, 1e-6);
    EXPECT_EQ(tu[4 * v + 3], -1.0f);
  }
}

TEST(TangentFrames, CylinderTangentIsTheAzimuthDirection) {
  // Radius 5, height 12 around z; u = azimuth / (pi/2) over a quarter, v = 1 - z / 12.
  const double r = 5.0;
  const auto cyl = grid(16, [&](double s, double t) {
    const double phi = s * std::numbers::pi / 2;
    return std::tuple{Vec3(r * std::cos(phi), r * std::sin(phi), 12 * t), Vec3(std::cos(phi), std::sin(phi), 0),
                      Eigen::Vector2d(s, 1.0 - t)};
  });
  const auto t = ctsurg::tangent_frames(cyl.vertices, cyl.normals, cyl.triangles, cyl.uvs);
  for (std::size_t v = 0; v < cyl.vertices.size() / 3; ++v) {
    const Vec3 p(cyl.vertices[3 * v], cyl.vertices[3 * v + 1], cyl.vertices[3 * v + 2]);
    const double phi = std::atan2(p.y(), p.x());
    const Vec3 e_phi(-std::sin(phi), std::cos(phi), 0);
    // Flat facets approximate the circle: the tangent follows the azimuth to within half a facet.
    EXPECT_GT(tangent(t, v).dot(e_phi), std::cos(0.5 * std::numbers::pi / 2 / 16) - 1e-6) << v;
    EXPECT_NEAR(tangent(t, v).norm(), 1.0, 1e-6);
    EXPECT_NEAR(tangent(t, v).dot(Vec3(cyl.normals[3 * v], cyl.normals[3 * v + 1], cyl.normals[3 * v + 2])), 0.0, 1e-6);
    EXPECT_EQ(t[4 * v + 3], 1.0f);
  }
}

TEST(TangentFrames, AtlasOfASphereGivesOrthonormalRightHandedFrames) {
  ctsurg::ImageGeometry g;
  g.dims = {24, 24, 24};
  g.spacing = Vec3::Constant(2.0);
  ctsurg::Volume<float> f(g);
  for (int64_t k = 0; k < 24; ++k)
    for (int64_t j = 0; j < 24; ++j)
      for (int64_t i = 0; i < 24; ++i)
        f(i, j, k) = float(17.0 - (g.index_to_world(Vec3(double(i), double(j), double(k))) - Vec3(23.1, 22.7, 23.4)).norm());
  const ctsurg::SurfaceMesh s = ctsurg::marching_cubes(f, 0.0);
  const ctsurg::SurfaceMesh m = ctsurg::apply_uv_atlas(s, ctsurg::build_uv_atlas(s.vertices, s.triangles, {256, 2, 60.0}));
  const auto t = ctsurg::tangent_frames(m.vertices, m.normals, m.triangles, m.uvs);
  ASSERT_EQ(t.size(), 4 * std::size_t(m.vertex_count()));
  for (std::size_t v = 0; v < std::size_t(m.vertex_count()); ++v) {
    const Vec3 n(m.normals[3 * v], m.normals[3 * v + 1], m.normals[3 * v + 2]);
    EXPECT_NEAR(tangent(t, v).norm(), 1.0, 1e-5);
    EXPECT_NEAR(tangent(t, v).dot(n), 0.0, 1e-5);
    // The atlas maps each chart's second axis up the image: right-handed everywhere.
    EXPECT_EQ(t[4 * v + 3], 1.0f);
  }
  EXPECT_THROW(ctsurg::tangent_frames(m.vertices, m.normals, m.triangles, {}), ctsurg::InputError);
}

}  // namespace
