#include "ctsurg/preprocess/slice_stack.h"

#include "ctsurg/core/error.h"

#include <gtest/gtest.h>

#include <cmath>

using ctsurg::analyse_slice_stack;
using Eigen::Vector3d;

namespace {
const Vector3d kRow(1, 0, 0), kCol(0, 1, 0);
}

TEST(SliceStack, SortsShuffledAxialSlicesAndMeasuresStep) {
  std::vector<Vector3d> p{{0, 0, 10}, {0, 0, 0}, {0, 0, 5}, {0, 0, 2.5}, {0, 0, 7.5}};
  const auto s = analyse_slice_stack(kRow, kCol, p, "test");
  EXPECT_EQ(s.order, (std::vector<int>{1, 3, 2, 4, 0}));
  EXPECT_NEAR(s.mean_step_mm, 2.5, 1e-12);
  EXPECT_FALSE(s.uneven);
  EXPECT_NEAR(s.tilt_deg, 0.0, 1e-9);
  const auto g = s.geometry(4, 3, 0.5, 0.7, p[1]);
  EXPECT_EQ(g.dims[2], 5);
  EXPECT_NEAR(g.spacing[1], 0.7, 1e-12);
  EXPECT_NEAR((g.index_to_world({0, 0, 4}) - Vector3d(0, 0, 10)).norm(), 0.0, 1e-12);
}

TEST(SliceStack, DetectsGantryTiltAsShear) {
  // Tilted slice plane (as in the GE series): normal at 18.5 degrees to the table axis z.
  const double t = 18.5 * M_PI / 180.0;
  const Vector3d col(0, std::cos(t), -std::sin(t));
  std::vector<Vector3d> p;
  for (int k = 0; k < 6; ++k) p.push_back({-125, -123.5, 5.0 + 4.22 * k});
  const auto s = analyse_slice_stack(kRow, col, p, "test");
  EXPECT_NEAR(s.tilt_deg, 18.5, 1e-6);
  EXPECT_NEAR(s.mean_step_mm, 4.22, 1e-9);
  const auto g = s.geometry(8, 8, 0.5, 0.5, p[0]);
  EXPECT_FALSE(g.is_orthonormal());
  for (int k = 0; k < 6; ++k) EXPECT_NEAR((g.index_to_world({0, 0, double(k)}) - p[k]).norm(), 0.0, 1e-9);
}

TEST(SliceStack, FlagsUnevenGapsAndResamplesAtSmallestGap) {
  std::vector<Vector3d> p{{0, 0, 0}, {0, 0, 1}, {0, 0, 4}};
  const auto s = analyse_slice_stack(kRow, kCol, p, "test");
  EXPECT_TRUE(s.uneven);
  EXPECT_NEAR(s.min_gap_mm, 1.0, 1e-12);
  EXPECT_NEAR(s.max_gap_mm, 3.0, 1e-12);
  EXPECT_EQ(s.missing_slices, 2);  // the 3 mm gap is three 1 mm steps
  ctsurg::Volume<float> v(s.geometry(1, 1, 1, 1, p[0]));
  v.voxels = {0.f, 10.f, 40.f};  // value = 10 x z: linear, so interpolation is exact
  const auto r = ctsurg::resample_even_slices(v, s);
  ASSERT_EQ(r.geometry.dims[2], 5);
  EXPECT_NEAR(r.geometry.spacing[2], 1.0, 1e-12);
  for (int k = 0; k < 5; ++k) EXPECT_NEAR(r.voxels[k], 10.0 * k, 1e-5) << k;
}

TEST(SliceStack, RejectsDuplicatePositionsAndScatteredSlices) {
  EXPECT_THROW(analyse_slice_stack(kRow, kCol, {{0, 0, 0}, {0, 0, 1}, {0, 0, 1}}, "x"), ctsurg::InputError);
  EXPECT_THROW(analyse_slice_stack(kRow, kCol, {{0, 0, 0}}, "x"), ctsurg::InputError);
  EXPECT_THROW(analyse_slice_stack(kRow, kCol, {{0, 0, 0}, {20, 0, 1}, {0, 0, 2}}, "x"), ctsurg::InputError);
}
