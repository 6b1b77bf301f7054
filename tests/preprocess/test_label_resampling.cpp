#include "ctsurg/preprocess/label_resampling.h"

#include <gtest/gtest.h>

using namespace ctsurg;

TEST(LabelResampling, FlippedRowOrderIsRecoveredExactly) {
  ImageGeometry g;
  g.dims = {5, 4, 3};
  g.spacing = {0.5, 0.8, 2.0};
  g.origin = {10, -20, 5};
  Volume<uint16_t> ours(g);
  for (std::size_t n = 0; n < ours.voxels.size(); ++n) ours.voxels[n] = uint16_t(n % 7);
  // The same voxels stored with j reversed (origin at the last row, column direction negated).
  ImageGeometry flipped = g;
  flipped.origin = g.index_to_world({0, double(g.dims[1] - 1), 0});
  flipped.direction.col(1) = -g.direction.col(1);
  Volume<uint16_t> stored(flipped);
  for (int64_t k = 0; k < 3; ++k)
    for (int64_t j = 0; j < 4; ++j)
      for (int64_t i = 0; i < 5; ++i) stored(i, 3 - j, k) = ours(i, j, k);
  const auto r = resample_labels_nearest(stored, g);
  EXPECT_TRUE(r.exact());
  EXPECT_EQ(r.outside, 0);
  EXPECT_EQ(r.labels.voxels, ours.voxels);
}

TEST(LabelResampling, CoarserTargetPicksNearestAndCountsOutside) {
  ImageGeometry src;
  src.dims = {4, 4, 4};
  Volume<uint16_t> labels(src);
  for (int64_t k = 0; k < 4; ++k)
    for (int64_t j = 0; j < 4; ++j)
      for (int64_t i = 0; i < 4; ++i) labels(i, j, k) = uint16_t(i);
  ImageGeometry dst;
  dst.dims = {3, 1, 1};
  dst.spacing = {2.0, 1.0, 1.0};
  dst.origin = {0.9, 0, 0};  // centres at x = 0.9, 2.9, 4.9
  const auto r = resample_labels_nearest(labels, dst);
  EXPECT_FALSE(r.exact());
  EXPECT_NEAR(r.max_offset_mm, 0.1, 1e-9);
  EXPECT_EQ(r.labels.voxels, (std::vector<uint16_t>{1, 3, 0}));
  EXPECT_EQ(r.outside, 1);
}
