#include "ctsurg/preprocess/mask_cleanup.h"

#include "ctsurg/preprocess/tissue_selection.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ctsurg {
namespace {

Volume<uint16_t> empty_volume(int64_t n, double spacing = 1.0) {
  ImageGeometry g;
  g.dims = {n, n, n};
  g.spacing = Eigen::Vector3d::Constant(spacing);
  return Volume<uint16_t>(g, 0);
}

// Voxels whose centre is within [r_in, r_out] (voxel units) of (cx, cy, cz) get `label`.
void paint_shell(Volume<uint16_t>& v, double cx, double cy, double cz, double r_in, double r_out, uint16_t label) {
  const auto& d = v.geometry.dims;
  for (int64_t k = 0; k < d[2]; ++k)
    for (int64_t j = 0; j < d[1]; ++j)
      for (int64_t i = 0; i < d[0]; ++i) {
        const double r = std::sqrt((i - cx) * (i - cx) + (j - cy) * (j - cy) + (k - cz) * (k - cz));
        if (r >= r_in && r <= r_out) v(i, j, k) = label;
      }
}

TEST(MaskCleanup, FillHolesFillsAHollowBall) {
  for (const uint16_t label : {uint16_t{1}, uint16_t{5}}) {
    auto shell = empty_volume(32);
    paint_shell(shell, 15.5, 15.5, 15.5, 7.0, 11.0, label);
    auto ball = empty_volume(32);
    paint_shell(ball, 15.5, 15.5, 15.5, 0.0, 11.0, label);
    MaskCleanupOptions o;
    o.fill_holes = true;
    const auto filled = cleanup_mask(shell, o);
    EXPECT_EQ(filled.voxels, ball.voxels);
    EXPECT_LT(count_tissue_voxels(shell), count_tissue_voxels(ball));
  }
}

TEST(MaskCleanup, FillHolesLeavesOpenCavity) {
  auto cup = empty_volume(24);
  paint_shell(cup, 12, 12, 12, 4.0, 8.0, 1);
  for (int64_t k = 12; k < 24; ++k)  // cut a channel from the cavity to the border
    for (int64_t j = 11; j <= 13; ++j)
      for (int64_t i = 11; i <= 13; ++i) cup(i, j, k) = 0;
  MaskCleanupOptions o;
  o.fill_holes = true;
  EXPECT_EQ(cleanup_mask(cup, o).voxels, cup.voxels);
}

TEST(MaskCleanup, KeepLargestAndMinimumComponentSize) {
  auto v = empty_volume(40, 2.0);  // 8 mm^3 voxels
  paint_shell(v, 10, 10, 10, 0.0, 6.0, 1);   // ~900 voxels
  paint_shell(v, 30, 30, 30, 0.0, 3.0, 2);   // ~123 voxels (984 mm^3)
  v(0, 39, 0) = 1;                           // a single voxel (8 mm^3)
  const int64_t big = [&] {
    auto b = empty_volume(40, 2.0);
    paint_shell(b, 10, 10, 10, 0.0, 6.0, 1);
    return count_tissue_voxels(b);
  }();
  MaskCleanupOptions largest;
  largest.keep_largest = true;
  const auto l = cleanup_mask(v, largest);
  EXPECT_EQ(count_tissue_voxels(l), big);
  EXPECT_EQ(l(10, 10, 10), 1);
  EXPECT_EQ(l(30, 30, 30), 0);

  MaskCleanupOptions min_size;
  min_size.min_component_mm3 = 100.0;  // drops only the single voxel
  const auto m = cleanup_mask(v, min_size);
  EXPECT_EQ(count_tissue_voxels(m), count_tissue_voxels(v) - 1);
  EXPECT_EQ(m(30, 30, 30), 2);  // labels survive
  EXPECT_EQ(m(0, 39, 0), 0);
}

TEST(MaskCleanup, ClosingBridgesAThinGapOnly) {
  auto v = empty_volume(30);
  for (int64_t k = 8; k < 22; ++k)
    for (int64_t j = 8; j < 22; ++j)
      for (int64_t i = 8; i < 22; ++i)
        if (i != 15) v(i, j, k) = 3;  // a cube cut by a one-voxel slit
  MaskCleanupOptions o;
  o.closing_mm = 2.0;
  const auto c = cleanup_mask(v, o);
  EXPECT_EQ(c(15, 15, 15), 3);
  for (int64_t k = 9; k < 21; ++k)
    for (int64_t j = 9; j < 21; ++j) EXPECT_EQ(c(15, j, k), 3);
  EXPECT_EQ(c(5, 5, 5), 0);
  // Closing never removes tissue.
  for (size_t n = 0; n < v.voxels.size(); ++n)
    if (v.voxels[n]) {
      EXPECT_EQ(c.voxels[n], v.voxels[n]);
    }
}

TEST(MaskCleanup, NoOptionsIsIdentity) {
  auto v = empty_volume(12);
  paint_shell(v, 5, 5, 5, 2.0, 4.0, 1);
  EXPECT_EQ(cleanup_mask(v, {}).voxels, v.voxels);
}

}  // namespace
}  // namespace ctsurg
