// Normal map baking against an analytic surface: a bumpy sphere (synthetic_phantom.h,
// r = R (1 + eps cos(m theta) sin^n(theta) cos(n phi))) at full resolution is baked onto the smooth
// sphere of radius R extracted by marching cubes from a coarse lattice. At every texel the decoded
// normal (through the interpolated tangent frame) is compared with the analytic normal of the
// bumpy surface where the coarse normal's line meets it. The baseline is the flat normal map
// (0, 0, 1) everywhere, i.e. what a baker that ignored the detail field would produce. Label masks:
// the Gaussian-smoothed mask against the anti-aliased one (anti_aliased_mask.h), at 0.5 mm, at the
// heart CT's 1.5 mm, and from a 3 mm segmentation resampled to 1.5 mm (the bundled heart's mask).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "ctsurg/core/error.h"
#include "ctsurg/mesh/anti_aliased_mask.h"
#include "ctsurg/mesh/detail_field.h"
#include "ctsurg/mesh/marching_cubes.h"
#include "ctsurg/mesh/normal_map_baking.h"
#include "ctsurg/mesh/tangent_frames.h"
#include "ctsurg/mesh/uv_atlas.h"
#include "ctsurg/preprocess/synthetic_phantom.h"

namespace {

using Vec3 = Eigen::Vector3d;

ctsurg::PhantomShape bumpy_shape() {
  ctsurg::PhantomShape s;
  s.kind = ctsurg::PhantomKind::BumpySphere;
  s.centre_mm = Vec3(1.3, -0.7, 0.4);
  s.radius_mm = 20.0;
  s.bump_amplitude = 0.06;  // up to 1.2 mm off the sphere, within one 2.5 mm coarse cell
  s.bump_m = 3;
  s.bump_n = 4;
  return s;
}

// `value(p)` sampled at the nodes of a cube lattice of `spacing` mm around the centre.
template <class F>
ctsurg::Volume<float> sampled(const Vec3& centre, double half_mm, double spacing, F value) {
  ctsurg::ImageGeometry g;
  const auto n = static_cast<int64_t>(std::ceil(2.0 * half_mm / spacing)) + 1;
  g.dims = {n, n, n};
  g.spacing = Vec3::Constant(spacing);
  g.origin = centre - Vec3::Constant(0.5 * spacing * static_cast<double>(n - 1)) + Vec3(0.137, -0.091, 0.053);
  ctsurg::Volume<float> v(g);
  for (int64_t k = 0; k < n; ++k)
    for (int64_t j = 0; j < n; ++j)
      for (int64_t i = 0; i < n; ++i)
        v(i, j, k) = static_cast<float>(value(g.index_to_world(Vec3(double(i), double(j), double(k)))));
  return v;
}

// The smooth coarse sphere (radius R + offset_mm) with atlas and tangents.
ctsurg::SurfaceMesh coarse_sphere(const ctsurg::PhantomShape& shape, int size, double offset_mm = 0.0) {
  const auto field = sampled(shape.centre_mm, shape.radius_mm + 6.0, 2.5,
                             [&](const Vec3& p) { return shape.radius_mm + offset_mm - (p - shape.centre_mm).norm(); });
  const ctsurg::SurfaceMesh sphere = ctsurg::marching_cubes(field, 0.0);
  ctsurg::SurfaceMesh m =
      ctsurg::apply_uv_atlas(sphere, ctsurg::build_uv_atlas(sphere.vertices, sphere.triangles, {size, 4, 60.0}));
  m.tangents = ctsurg::tangent_frames(m.vertices, m.normals, m.triangles, m.uvs);
  return m;
}

struct AngularErrors {
  double baked_mean = 0.0, baked_p95 = 0.0, baked_max = 0.0, flat_mean = 0.0;
  int64_t texels = 0;
};

// Decoded normals against the analytic bumpy-sphere normals over every covered texel.
AngularErrors compare_with_analytic(const ctsurg::SurfaceMesh& m, const ctsurg::NormalMapImage& map,
                                    const ctsurg::PhantomShape& shape) {
  const int size = static_cast<int>(map.width);
  const auto owner = ctsurg::texel_owners(m.uvs, m.triangles, size);
  const auto V = [&](uint32_t v, const std::vector<float>& a, int w) {
    return Vec3(a[std::size_t(w) * v], a[std::size_t(w) * v + 1], a[std::size_t(w) * v + 2]);
  };
  const auto angle = [](const Vec3& a, const Vec3& b) {
    return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / std::numbers::pi;
  };
  AngularErrors e;
  std::vector<double> errors;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const int32_t t = owner[std::size_t(y) * std::size_t(size) + std::size_t(x)];
      if (t < 0) continue;
      const uint32_t* v = &m.triangles[3 * std::size_t(t)];
      Eigen::Vector2d q[3];
      for (int c = 0; c < 3; ++c) q[c] = Eigen::Vector2d(m.uvs[2 * v[c]] * size, m.uvs[2 * v[c] + 1] * size);
      const Eigen::Vector2d px(x + 0.5, y + 0.5);
      const auto cross2 = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); };
      const double area = cross2(q[1] - q[0], q[2] - q[0]);
      double l[3] = {0, cross2(px - q[0], q[2] - q[0]) / area, cross2(q[1] - q[0], px - q[0]) / area};
      l[0] = 1.0 - l[1] - l[2];
      for (double& li : l) li = std::max(li, 0.0);
      const double sum = l[0] + l[1] + l[2];
      Vec3 P = Vec3::Zero(), N = Vec3::Zero(), T = Vec3::Zero();
      double w = 0.0;
      for (int c = 0; c < 3; ++c) {
        P += l[c] / sum * V(v[c], m.vertices, 3);
        N += l[c] / sum * V(v[c], m.normals, 3);
        T += l[c] / sum * V(v[c], m.tangents, 4);
        w += l[c] * m.tangents[4 * std::size_t(v[c]) + 3];
      }
      N.normalize();
      T = (T - N * N.dot(T)).normalized();
      const Vec3 B = (w < 0 ? -1.0 : 1.0) * N.cross(T);
      const Vec3 ts = ctsurg::decode_normal_map_texel(map, x, y);
      const Vec3 baked = ts.x() * T + ts.y() * B + ts.z() * N;
      // The bumpy surface where the coarse normal's line through P meets it (the coarse normal is
      // radial to within a degree, so this is the surface point in P's direction from the centre).
      const Vec3 d = (P - shape.centre_mm).normalized();
      const double theta = std::acos(std::clamp(d.z(), -1.0, 1.0)), phi = std::atan2(d.y(), d.x());
      const Vec3 truth = ctsurg::phantom_outward_normal(shape, ctsurg::bumpy_sphere_surface_point(shape, theta, phi));
      const double err = angle(baked, truth);
      e.baked_mean += err;
      e.baked_max = std::max(e.baked_max, err);
      errors.push_back(err);
      e.flat_mean += angle(N, truth);
      ++e.texels;
    }
  e.baked_mean /= double(e.texels);
  e.flat_mean /= double(e.texels);
  std::sort(errors.begin(), errors.end());
  e.baked_p95 = errors[errors.size() * 95 / 100];
  return e;
}

// A 0/1 tissue mask of the shape on a cube lattice of `voxel_mm` around it. With block > 1 the shape
// is segmented at block x voxel_mm and resampled by nearest neighbour (every voxel takes the value at
// its block's centre; blocks start at index 1), as ctsurg-grid resamples a coarser mask to the CT.
ctsurg::Volume<uint16_t> phantom_mask(const ctsurg::PhantomShape& shape, double voxel_mm, int block = 1) {
  const auto grid = sampled(shape.centre_mm, shape.radius_mm * (1.0 + shape.bump_amplitude) + 4.0, voxel_mm,
                            [](const Vec3&) { return 0.0; });
  const auto& g = grid.geometry;
  ctsurg::Volume<uint16_t> labels(g, 0);
  const auto centre = [&](int64_t i) {
    return block == 1 ? double(i) : double(((i + block - 1) / block) * block - (block - 1)) + 0.5 * (block - 1);
  };
  for (int64_t k = 0; k < g.dims[2]; ++k)
    for (int64_t j = 0; j < g.dims[1]; ++j)
      for (int64_t i = 0; i < g.dims[0]; ++i)
        labels(i, j, k) = ctsurg::phantom_contains(shape, g.index_to_world(Vec3(centre(i), centre(j), centre(k)))) ? 1 : 0;
  return labels;
}

void print_row(const char* what, const AngularErrors& e) {
  std::printf("  %-44s %6lld texels, error mean %.2f, p95 %.2f, max %.2f deg (flat map %.2f)\n", what,
              static_cast<long long>(e.texels), e.baked_mean, e.baked_p95, e.baked_max, e.flat_mean);
}

TEST(NormalMapBaking, BumpySphereFromImplicitFieldMatchesAnalyticNormals) {
  const ctsurg::PhantomShape shape = bumpy_shape();
  const ctsurg::SurfaceMesh m = coarse_sphere(shape, 384);
  // Full resolution: minus the radial gap (inside = high), 0.5 mm voxels, lightly smoothed.
  const auto values = sampled(shape.centre_mm, 24.0, 0.5, [&](const Vec3& p) { return -ctsurg::phantom_implicit_mm(shape, p); });
  const ctsurg::DetailField field = ctsurg::detail_field_from_values(values, 0.0, 0.5);
  ctsurg::NormalMapBakeStats stats;
  const ctsurg::NormalMapImage map = ctsurg::bake_normal_map(m, field, {384, 8, 2, 0.0, 0}, &stats);
  ASSERT_EQ(map.width, 384);
  EXPECT_GT(stats.texels_covered, 30000);
  EXPECT_EQ(stats.texels_on_crossing, stats.texels_covered);  // every texel is within 1.2 mm of the bumps
  const AngularErrors e = compare_with_analytic(m, map, shape);
  RecordProperty("baked_mean_deg", std::to_string(e.baked_mean));
  RecordProperty("baked_max_deg", std::to_string(e.baked_max));
  RecordProperty("flat_mean_deg", std::to_string(e.flat_mean));
  std::printf("bumpy sphere (implicit field): %lld texels, mean error %.3f deg (max %.3f), flat baseline %.3f deg\n",
              static_cast<long long>(e.texels), e.baked_mean, e.baked_max, e.flat_mean);
  // The bumps tilt the normal by about 4.9 deg on average (a baker ignoring the field is that far
  // off); the baked map recovers them to about 0.18 deg mean, 0.46 deg max (8-bit quantisation
  // alone is up to about 0.3 deg).
  EXPECT_GT(e.flat_mean, 4.0);
  EXPECT_LT(e.baked_mean, 0.5);
  EXPECT_LT(e.baked_max, 2.0);
}

TEST(NormalMapBaking, BumpySphereFromLabelMaskIsCloseToAnalyticNormals) {
  // The paths the tool takes for an occupancy grid: a 0/1 tissue mask at 0.5 mm, Gaussian-smoothed
  // (--detail gaussian) or anti-aliased (the default).
  const ctsurg::PhantomShape shape = bumpy_shape();
  const ctsurg::SurfaceMesh m = coarse_sphere(shape, 256);
  const ctsurg::Volume<uint16_t> labels = phantom_mask(shape, 0.5);
  const auto bake = [&](const ctsurg::DetailField& field) {
    return compare_with_analytic(m, ctsurg::bake_normal_map(m, field, {256, 16, 2, 0.0, 0}), shape);
  };
  const AngularErrors voxel = bake(ctsurg::detail_field_from_labels(labels, 0.5));
  const AngularErrors gauss = bake(ctsurg::detail_field_from_labels(labels, 0.75));
  const AngularErrors aa = bake(ctsurg::detail_field_from_anti_aliased_labels(labels));
  std::printf("bumpy sphere R 20 mm, label mask at 0.5 mm:\n");
  print_row("Gaussian sigma 0.5 mm (one voxel)", voxel);
  print_row("Gaussian sigma 0.75 mm", gauss);
  print_row("anti-aliased", aa);
  // Measured: 3.00 / 6.68 / 16.5 deg (mean / p95 / max), 1.45 / 3.27 / 8.8, 0.89 / 2.05 / 5.0; the
  // flat map 4.9 deg.
  EXPECT_LT(gauss.baked_mean, 2.5);
  EXPECT_LT(gauss.baked_mean, 0.4 * gauss.flat_mean);
  EXPECT_LT(aa.baked_mean, 1.2);
  EXPECT_LT(aa.baked_mean, 0.7 * gauss.baked_mean);
  EXPECT_LT(aa.baked_p95, 0.7 * gauss.baked_p95);
  EXPECT_LT(aa.baked_max, 0.7 * gauss.baked_max);
  EXPECT_LT(aa.baked_mean, 0.35 * voxel.baked_mean);
}

TEST(NormalMapBaking, StaircaseOfCoarseMasksIsRemovedByTheAntiAliasedField) {
  // Masks like the heart's: at the CT's 1.5 mm, and segmented at 3 mm then resampled to 1.5 mm (the
  // bundled heart's mask, whose terraces are 3 mm steps), on a bumpy sphere of R 25 mm (bumps up to
  // 1.5 mm). The tool's old default was the Gaussian of one voxel (1.5 mm).
  ctsurg::PhantomShape shape = bumpy_shape();
  shape.radius_mm = 25.0;
  const ctsurg::SurfaceMesh m = coarse_sphere(shape, 256);
  const auto bake = [&](const ctsurg::DetailField& field) {
    return compare_with_analytic(m, ctsurg::bake_normal_map(m, field, {256, 16, 2, 0.0, 0}), shape);
  };
  const ctsurg::Volume<uint16_t> ct_voxels = phantom_mask(shape, 1.5), resampled = phantom_mask(shape, 1.5, 2);
  const AngularErrors gauss = bake(ctsurg::detail_field_from_labels(ct_voxels, 1.5));
  const AngularErrors gauss2 = bake(ctsurg::detail_field_from_labels(ct_voxels, 3.0));
  const AngularErrors aa = bake(ctsurg::detail_field_from_anti_aliased_labels(ct_voxels));
  ctsurg::AntiAliasStats stats;
  const AngularErrors gauss_resampled = bake(ctsurg::detail_field_from_labels(resampled, 1.5));
  const AngularErrors aa_resampled = bake(ctsurg::detail_field_from_anti_aliased_labels(resampled, {}, &stats));
  std::printf("bumpy sphere R 25 mm, label mask at 1.5 mm:\n");
  print_row("Gaussian sigma 1.5 mm (one voxel)", gauss);
  print_row("Gaussian sigma 3 mm", gauss2);
  print_row("anti-aliased", aa);
  std::printf("... segmented at 3 mm, resampled to 1.5 mm:\n");
  print_row("Gaussian sigma 1.5 mm", gauss_resampled);
  print_row("anti-aliased (on the 3 mm blocks)", aa_resampled);
  // Measured: 3.16 / 6.99 / 16.1, 1.37 / 2.66 / 3.93, 1.00 / 2.05 / 3.14; resampled 9.94 / 17.8 /
  // 26.8 and 2.81 / 5.65 / 7.62; the flat map 4.9 deg.
  EXPECT_LT(aa.baked_mean, 0.4 * gauss.baked_mean);
  EXPECT_LT(aa.baked_p95, 0.4 * gauss.baked_p95);
  EXPECT_LT(aa.baked_max, 0.3 * gauss.baked_max);
  EXPECT_LT(aa.baked_mean, 0.85 * gauss2.baked_mean);
  EXPECT_EQ(stats.blocks.factor, (std::array<int, 3>{2, 2, 2}));
  EXPECT_GT(gauss_resampled.baked_mean, 1.5 * gauss_resampled.flat_mean);  // the terraces: worse than no map
  EXPECT_LT(aa_resampled.baked_mean, 0.35 * gauss_resampled.baked_mean);
  EXPECT_LT(aa_resampled.baked_max, 0.35 * gauss_resampled.baked_max);
  EXPECT_LT(aa_resampled.baked_mean, 0.65 * aa_resampled.flat_mean);
}

TEST(NormalMapBaking, SearchAlongTheNormalFindsDetailOffTheCoarseSurface) {
  // The coarse sphere 1.8 mm outside the bumpy surface (as a coarse grid's surface can sit off the
  // detailed one) and a mask smoothed with sigma 0.5 mm (kernel cut at 1.5 mm): at most texels the
  // field is flat at the texel's own point, so only the search along the normal for the nearest
  // crossing recovers the detailed normal.
  const ctsurg::PhantomShape shape = bumpy_shape();
  const ctsurg::SurfaceMesh m = coarse_sphere(shape, 192, 1.8);
  const auto inside =
      sampled(shape.centre_mm, 25.0, 0.5, [&](const Vec3& p) { return ctsurg::phantom_contains(shape, p) ? 1.0 : 0.0; });
  ctsurg::Volume<uint16_t> labels(inside.geometry);
  for (std::size_t i = 0; i < labels.voxels.size(); ++i) labels.voxels[i] = inside.voxels[i] > 0.5f ? 1 : 0;
  const ctsurg::DetailField field = ctsurg::detail_field_from_labels(labels, 0.5);
  ctsurg::NormalMapBakeStats with_stats;
  const auto with = compare_with_analytic(m, ctsurg::bake_normal_map(m, field, {192, 8, 2, 4.0, 0}, &with_stats), shape);
  const auto without = compare_with_analytic(m, ctsurg::bake_normal_map(m, field, {192, 8, 2, 0.01, 0}), shape);
  std::printf(
      "coarse surface 1.8 mm off the bumps: mean error %.3f deg with the search (%.1f %% on a crossing), %.3f deg "
      "without, flat %.3f deg\n",
      with.baked_mean, 100.0 * double(with_stats.texels_on_crossing) / double(with_stats.texels_covered), without.baked_mean,
      with.flat_mean);
  // Measured: 3.0 deg with the search (the staircase of a 0.5 mm mask at sigma 0.5 mm), 10.0 deg
  // without (the field's faint far-field slope), 4.9 deg for the flat map.
  EXPECT_GT(double(with_stats.texels_on_crossing), 0.99 * double(with_stats.texels_covered));
  EXPECT_LT(with.baked_mean, 0.5 * without.baked_mean);
  EXPECT_LT(with.baked_mean, 0.8 * with.flat_mean);
}

TEST(NormalMapBaking, ResultDoesNotDependOnThreadsAndFlatFieldGivesFlatMap) {
  const ctsurg::PhantomShape shape = bumpy_shape();
  const ctsurg::SurfaceMesh m = coarse_sphere(shape, 128);
  // A field whose level set is the coarse sphere itself: every baked normal is the mesh normal to
  // within the difference between the mesh and the true sphere.
  const auto values =
      sampled(shape.centre_mm, 24.0, 0.5, [&](const Vec3& p) { return shape.radius_mm - (p - shape.centre_mm).norm(); });
  const ctsurg::DetailField field = ctsurg::detail_field_from_values(values, 0.0, 0.0);
  const auto one = ctsurg::bake_normal_map(m, field, {128, 8, 3, 0.0, 1});
  const auto two = ctsurg::bake_normal_map(m, field, {128, 8, 3, 0.0, 2});
  EXPECT_EQ(one.rgb, two.rgb);
  ctsurg::NormalMapBakeStats stats;
  ctsurg::bake_normal_map(m, field, {128, 8, 3, 0.0, 2}, &stats);
  EXPECT_LT(stats.mean_tilt_deg, 2.0);
  EXPECT_GT(stats.texels_dilated, 0);
  // Background texels far from every chart stay flat: (0, 0, 1) -> (128, 128, 255).
  const auto owner = ctsurg::texel_owners(m.uvs, m.triangles, 128);
  EXPECT_EQ(owner[128 * 128 - 1], -1);
  EXPECT_EQ(one.rgb[3 * (128 * 128 - 1) + 2], 255);
}

TEST(NormalMapBaking, RejectsMeshWithoutUvsAndBadOptions) {
  ctsurg::SurfaceMesh m;
  m.vertices = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  m.normals = {0, 0, 1, 0, 0, 1, 0, 0, 1};
  m.triangles = {0, 1, 2};
  ctsurg::DetailField field;
  field.values = ctsurg::Volume<float>(ctsurg::ImageGeometry{{4, 4, 4}}, 0.0f);
  EXPECT_THROW(ctsurg::bake_normal_map(m, field, {}), ctsurg::InputError);
  m.uvs = {0.1f, 0.1f, 0.9f, 0.1f, 0.1f, 0.9f};
  m.tangents = {1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1};
  EXPECT_THROW(ctsurg::bake_normal_map(m, field, {64, 12, 2, 0.0, 0}), ctsurg::InputError);
  EXPECT_NO_THROW(ctsurg::bake_normal_map(m, field, {64, 8, 2, 0.0, 0}));
}

}  // namespace
