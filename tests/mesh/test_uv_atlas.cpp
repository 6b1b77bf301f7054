// UV atlas properties on closed marching-cubes surfaces of several shapes and atlas sizes: UVs in
// [0, 1], consistent orientation, no texel touched by two charts (conservative rasterisation),
// the padding between charts, bounded stretch at one common density, seams that copy vertices
// exactly, and determinism.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "ctsurg/core/error.h"
#include "ctsurg/mesh/marching_cubes.h"
#include "ctsurg/mesh/uv_atlas.h"
#include "ctsurg/preprocess/synthetic_phantom.h"

namespace {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;

ctsurg::SurfaceMesh surface_of(const ctsurg::PhantomShape& shape, double spacing) {
  const Vec3 h = ctsurg::phantom_half_extent_mm(shape) + Vec3::Constant(2.0 * spacing);
  ctsurg::ImageGeometry g;
  for (int a = 0; a < 3; ++a) g.dims[std::size_t(a)] = static_cast<int64_t>(std::ceil(2.0 * h[a] / spacing)) + 1;
  g.spacing = Vec3::Constant(spacing);
  g.origin = shape.centre_mm - h + Vec3(0.21, -0.33, 0.12) * spacing;
  ctsurg::Volume<float> f(g);
  for (int64_t k = 0; k < g.dims[2]; ++k)
    for (int64_t j = 0; j < g.dims[1]; ++j)
      for (int64_t i = 0; i < g.dims[0]; ++i)
        f(i, j, k) =
            static_cast<float>(-ctsurg::phantom_implicit_mm(shape, g.index_to_world(Vec3(double(i), double(j), double(k)))));
  return ctsurg::marching_cubes(f, 0.0);
}

std::vector<ctsurg::PhantomShape> shapes() {
  ctsurg::PhantomShape sphere, torus, shell, bumpy;
  sphere.kind = ctsurg::PhantomKind::Sphere;
  torus.kind = ctsurg::PhantomKind::Torus;
  shell.kind = ctsurg::PhantomKind::EllipsoidShell;
  bumpy.kind = ctsurg::PhantomKind::BumpySphere;
  bumpy.bump_amplitude = 0.25;
  return {sphere, torus, shell, bumpy};
}

// Separating-axis overlap of a triangle and the open texel square [x, x+1] x [y, y+1].
bool touches(const std::array<Vec2, 3>& t, int x, int y) {
  const std::array<Vec2, 4> sq{Vec2(x, y), Vec2(x + 1, y), Vec2(x + 1, y + 1), Vec2(x, y + 1)};
  std::vector<Vec2> axes{Vec2(1, 0), Vec2(0, 1)};
  for (int e = 0; e < 3; ++e) {
    const Vec2 d = t[std::size_t((e + 1) % 3)] - t[std::size_t(e)];
    axes.emplace_back(-d.y(), d.x());
  }
  for (const Vec2& a : axes) {
    double t0 = 1e300, t1 = -1e300, s0 = 1e300, s1 = -1e300;
    for (const Vec2& p : t) t0 = std::min(t0, a.dot(p)), t1 = std::max(t1, a.dot(p));
    for (const Vec2& p : sq) s0 = std::min(s0, a.dot(p)), s1 = std::max(s1, a.dot(p));
    if (t1 <= s0 || s1 <= t0) return false;
  }
  return true;
}

void check_atlas(const ctsurg::SurfaceMesh& mesh, int size, int pad, const std::string& what) {
  SCOPED_TRACE(what);
  const ctsurg::UvAtlas atlas = ctsurg::build_uv_atlas(mesh.vertices, mesh.triangles, {size, pad, 60.0});
  const std::size_t nf = mesh.triangles.size() / 3, nv = atlas.source_vertex.size();
  ASSERT_EQ(atlas.triangles.size(), mesh.triangles.size());
  ASSERT_EQ(atlas.uvs.size(), 2 * nv);
  EXPECT_GE(nv, std::size_t(mesh.vertex_count()));
  EXPECT_GT(atlas.fill_ratio, 0.25);
  EXPECT_LT(atlas.fill_ratio, 1.0);
  for (const float u : atlas.uvs) {
    ASSERT_GE(u, 0.0f);
    ASSERT_LE(u, 1.0f);
  }
  // Every copy of a vertex lies where its source does, and each triangle is the same triangle.
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) EXPECT_EQ(atlas.source_vertex[atlas.triangles[t]], mesh.triangles[t]);
  // Conservative coverage per chart; stretch and orientation per triangle.
  std::vector<int32_t> chart_at(std::size_t(size) * std::size_t(size), -1);
  int64_t shared = 0;
  const double s = atlas.texels_per_mm;
  const double cos_max = std::cos(60.0 * std::numbers::pi / 180.0), cos_merge = std::cos(80.0 * std::numbers::pi / 180.0);
  double total_area = 0.0, merged_area = 0.0;
  for (std::size_t t = 0; t < nf; ++t) {
    std::array<Vec2, 3> q;
    Vec3 p[3];
    for (int c = 0; c < 3; ++c) {
      const uint32_t v = atlas.triangles[3 * t + std::size_t(c)];
      q[std::size_t(c)] = Vec2(atlas.uvs[2 * v] * size, atlas.uvs[2 * v + 1] * size);
      const uint32_t o = mesh.triangles[3 * t + std::size_t(c)];
      p[c] = Vec3(mesh.vertices[3 * o], mesh.vertices[3 * o + 1], mesh.vertices[3 * o + 2]);
    }
    const Vec2 e1 = q[1] - q[0], e2 = q[2] - q[0];
    const double uv_area = 0.5 * (e1.x() * e2.y() - e1.y() * e2.x());  // texels^2, negative: v runs down
    const double area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).norm();
    if (area > 1e-6) {
      EXPECT_LT(uv_area, 0.0) << "triangle " << t << " flipped";
      const double ratio = -uv_area / (area * s * s);
      EXPECT_GE(ratio, cos_merge - 1e-3) << "triangle " << t;
      EXPECT_LE(ratio, 1.0 + 1e-3) << "triangle " << t;
      total_area += area;
      if (ratio < cos_max - 1e-3) merged_area += area;  // only triangles of merged small charts
    }
    const int chart = atlas.triangle_chart[t];
    const int x0 = std::max(0, int(std::floor(std::min({q[0].x(), q[1].x(), q[2].x()})))),
              x1 = std::min(size - 1, int(std::max({q[0].x(), q[1].x(), q[2].x()})));
    const int y0 = std::max(0, int(std::floor(std::min({q[0].y(), q[1].y(), q[2].y()})))),
              y1 = std::min(size - 1, int(std::max({q[0].y(), q[1].y(), q[2].y()})));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        if (!touches(q, x, y)) continue;
        int32_t& c = chart_at[std::size_t(y) * std::size_t(size) + std::size_t(x)];
        if (c >= 0 && c != chart) ++shared;
        c = chart;
      }
  }
  EXPECT_EQ(shared, 0) << "texels touched by two charts";
  // Stretch beyond the 60 deg bound is confined to a sliver of the surface.
  EXPECT_LT(merged_area, 0.01 * total_area);
  // Padding: no texel of another chart within `pad` texels (Chebyshev) of a chart's texel, and
  // nothing in the outer `pad` texels... minus one: the border margin is pad texels wide.
  int64_t too_close = 0, on_border = 0;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const int32_t c = chart_at[std::size_t(y) * std::size_t(size) + std::size_t(x)];
      if (c < 0) continue;
      if (x < pad || y < pad || x >= size - pad || y >= size - pad) ++on_border;
      for (int dy = -pad; dy <= pad; ++dy)
        for (int dx = -pad; dx <= pad; ++dx) {
          const int xx = x + dx, yy = y + dy;
          if (xx < 0 || yy < 0 || xx >= size || yy >= size) continue;
          const int32_t o = chart_at[std::size_t(yy) * std::size_t(size) + std::size_t(xx)];
          if (o >= 0 && o != c) ++too_close;
        }
    }
  EXPECT_EQ(too_close, 0);
  EXPECT_EQ(on_border, 0);
  // Deterministic.
  const ctsurg::UvAtlas again = ctsurg::build_uv_atlas(mesh.vertices, mesh.triangles, {size, pad, 60.0});
  EXPECT_EQ(again.uvs, atlas.uvs);
  EXPECT_EQ(again.triangles, atlas.triangles);
}

TEST(UvAtlas, ChartsDoNotOverlapAndKeepPaddingOnSeveralShapes) {
  for (const auto& shape : shapes()) {
    const ctsurg::SurfaceMesh mesh = surface_of(shape, 2.0);
    const std::string name = ctsurg::phantom_kind_name(shape.kind);
    check_atlas(mesh, 256, 2, name + " 256");
    // A larger atlas and padding on the two shapes with the most charts (kept short for sanitizer builds).
    if (shape.kind == ctsurg::PhantomKind::Torus || shape.kind == ctsurg::PhantomKind::BumpySphere)
      check_atlas(mesh, 512, 4, name + " 512");
  }
}

TEST(UvAtlas, ApplyCopiesPerVertexDataThroughSourceVertex) {
  ctsurg::PhantomShape sphere;
  const ctsurg::SurfaceMesh mesh = surface_of(sphere, 2.5);
  const ctsurg::UvAtlas atlas = ctsurg::build_uv_atlas(mesh.vertices, mesh.triangles, {256, 2, 60.0});
  const ctsurg::SurfaceMesh m = ctsurg::apply_uv_atlas(mesh, atlas);
  ASSERT_EQ(m.vertex_count(), int64_t(atlas.source_vertex.size()));
  EXPECT_GT(m.vertex_count(), mesh.vertex_count());  // seams duplicate vertices
  EXPECT_EQ(m.source_vertex_count, mesh.vertex_count());
  for (int64_t v = 0; v < m.vertex_count(); ++v) {
    const std::size_t o = m.source_vertex[std::size_t(v)];
    for (int c = 0; c < 3; ++c) ASSERT_EQ(m.vertices[3 * std::size_t(v) + std::size_t(c)], mesh.vertices[3 * o + std::size_t(c)]);
    for (int c = 0; c < 8; ++c)
      ASSERT_EQ(m.grid_weights[8 * std::size_t(v) + std::size_t(c)], mesh.grid_weights[8 * o + std::size_t(c)]);
    for (int c = 0; c < 3; ++c)
      ASSERT_EQ(m.grid_cell[3 * std::size_t(v) + std::size_t(c)], mesh.grid_cell[3 * o + std::size_t(c)]);
    for (int c = 0; c < 3; ++c)
      ASSERT_EQ(m.nearest_node[3 * std::size_t(v) + std::size_t(c)], mesh.nearest_node[3 * o + std::size_t(c)]);
  }
  // A sphere needs at least the six axis charts.
  EXPECT_GE(atlas.chart_count, 6);
}

TEST(UvAtlas, RejectsBadOptionsAndTooSmallAtlas) {
  ctsurg::PhantomShape sphere;
  const ctsurg::SurfaceMesh mesh = surface_of(sphere, 2.5);
  EXPECT_THROW(ctsurg::build_uv_atlas(mesh.vertices, mesh.triangles, {8, 1, 60.0}), ctsurg::InputError);
  EXPECT_THROW(ctsurg::build_uv_atlas(mesh.vertices, mesh.triangles, {256, 0, 60.0}), ctsurg::InputError);
  EXPECT_THROW(ctsurg::build_uv_atlas(mesh.vertices, mesh.triangles, {256, 2, 90.0}), ctsurg::InputError);
  EXPECT_THROW(ctsurg::build_uv_atlas({}, {}, {}), ctsurg::InputError);
  // 16 texels with 2 of padding hold at most 9 charts (each at least 2 x 2 texels plus 2 of
  // padding: 3 per row, 3 rows); the bumpy sphere cut at 30 deg has more.
  const ctsurg::SurfaceMesh bumpy = surface_of(shapes()[3], 2.0);
  ASSERT_GT(ctsurg::build_uv_atlas(bumpy.vertices, bumpy.triangles, {256, 2, 30.0}).chart_count, 9);
  EXPECT_THROW(ctsurg::build_uv_atlas(bumpy.vertices, bumpy.triangles, {16, 2, 30.0}), ctsurg::RuntimeError);
}

}  // namespace
