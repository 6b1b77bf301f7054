#include "ctsurg/preprocess/occupancy_downsampling.h"

#include "ctsurg/core/error.h"
#include "ctsurg/preprocess/image_file_reader.h"
#include "ctsurg/preprocess/tissue_selection.h"
#include "test_support.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace ctsurg {
namespace {

Volume<uint16_t> ball_mask(const Eigen::Vector3d& spacing, double radius_mm, int64_t n, uint16_t label = 1) {
  ImageGeometry g;
  g.dims = {n, n, n};
  g.spacing = spacing;
  g.origin = Eigen::Vector3d(-12.0, 7.0, 30.0);
  Volume<uint16_t> v(g, 0);
  const Eigen::Vector3d centre = 0.5 * spacing.cwiseProduct(Eigen::Vector3d::Constant(double(n - 1)));
  for (int64_t k = 0; k < n; ++k)
    for (int64_t j = 0; j < n; ++j)
      for (int64_t i = 0; i < n; ++i) {
        const Eigen::Vector3d p = spacing.cwiseProduct(Eigen::Vector3d(double(i), double(j), double(k))) + Eigen::Vector3d(0.3, -0.2, 0.1);
        if ((p - centre).norm() <= radius_mm) v(i, j, k) = label;
      }
  return v;
}

double sum(const std::vector<float>& v) {
  double s = 0.0;
  for (const float f : v) s += f;
  return s;
}

// Brute force: |box(voxel) ∩ cell| summed over the voxels of `label`, one 3D box intersection per
// (voxel, cell) pair, in the CT's index frame.
double brute_force_fraction(const Volume<uint16_t>& mask, const ImageGeometry& cells, int64_t ci, int64_t cj, int64_t ck,
                            uint16_t label) {
  const auto& g = mask.geometry;
  const double h = cells.spacing[0];
  const Eigen::Vector3d c0 = g.world_to_index(cells.index_to_world(Eigen::Vector3d(double(ci), double(cj), double(ck))));
  double volume = 0.0;
  for (int64_t k = 0; k < g.dims[2]; ++k)
    for (int64_t j = 0; j < g.dims[1]; ++j)
      for (int64_t i = 0; i < g.dims[0]; ++i) {
        if (mask(i, j, k) != label) continue;
        const int64_t ijk[3] = {i, j, k};
        double v = 1.0;
        for (int a = 0; a < 3; ++a) {
          const double s = g.spacing[a];
          const double lo = std::max((double(ijk[a]) - 0.5) * s, c0[a] * s - 0.5 * h);
          const double hi = std::min((double(ijk[a]) + 0.5) * s, c0[a] * s + 0.5 * h);
          v *= std::max(0.0, hi - lo);
        }
        volume += v;
      }
  return volume / (h * h * h);
}

TEST(OccupancyDownsampling, FractionsConserveTheMaskVolumeAndApproachTheBall) {
  const double radius = 10.0;
  const double analytic = 4.0 / 3.0 * std::numbers::pi * radius * radius * radius;  // 4188.8 mm^3
  for (const Eigen::Vector3d& spacing : {Eigen::Vector3d(0.5, 0.5, 0.5), Eigen::Vector3d(0.5, 0.7, 0.9)}) {
    const auto mask = ball_mask(spacing, radius, int64_t(std::ceil(24.0 / spacing.minCoeff())));
    const double mask_mm3 = double(count_tissue_voxels(mask)) * mask.geometry.voxel_volume_mm3();
    EXPECT_NEAR(mask_mm3, analytic, 0.02 * analytic);  // voxelisation of the ball
    for (const double h : {0.37, 1.0, 1.5, 2.4, 3.3, 7.0}) {
      OccupancyDownsamplingOptions o;
      o.cell_mm = h;
      const auto grid = downsample_occupancy(mask, o, {{1, "tissue"}});
      const double cells_mm3 = sum(grid.fraction.voxels) * h * h * h;
      // Exact volume fractions conserve the voxel volume (float storage: 1e-5 relative).
      EXPECT_NEAR(cells_mm3, mask_mm3, 1e-5 * mask_mm3) << "h " << h;
      for (const float f : grid.fraction.voxels) {
        ASSERT_GE(f, 0.0f);
        ASSERT_LE(f, 1.0f);
      }
      EXPECT_DOUBLE_EQ(grid.occupancy.geometry.spacing[1], h);
      EXPECT_DOUBLE_EQ(grid.occupancy.geometry.spacing[2], h);
      // Particle volume approaches the ball when cells are small.
      if (h <= 1.5) {
        EXPECT_NEAR(double(grid.particle_count()) * h * h * h, analytic, 0.05 * analytic) << h;
      }
    }
  }
}

TEST(OccupancyDownsampling, HandComputedFractionForNonIntegerRatio) {
  // Three 1.5 mm voxels in a row, 2.4 mm cells: the 4.5 mm run is covered by two cells centred on
  // it, [-2.4, 0] and [0, 2.4] mm from its centre; each gets 2.25 mm of it along x and the single
  // voxel's 1.5 mm (inside one cell) along y and z: fraction 2.25 * 1.5 * 1.5 / 2.4^3 = 0.3662109.
  ImageGeometry g;
  g.dims = {9, 5, 5};
  g.spacing = Eigen::Vector3d::Constant(1.5);
  Volume<uint16_t> mask(g, 0);
  for (int64_t i = 3; i <= 5; ++i) mask(i, 2, 2) = 1;
  OccupancyDownsamplingOptions o;
  o.cell_mm = 2.4;
  o.occupancy_threshold = 0.3;
  const auto grid = downsample_occupancy(mask, o, {});
  EXPECT_EQ(grid.occupancy.geometry.dims, (std::array<int64_t, 3>{4, 3, 3}));  // 2 x 1 x 1 plus margins
  EXPECT_NEAR(grid.fraction(1, 1, 1), 0.3662109375, 1e-6);
  EXPECT_NEAR(grid.fraction(2, 1, 1), 0.3662109375, 1e-6);
  EXPECT_EQ(grid.particle_count(), 2);
  // The lattice is centred on the run: cell centres at voxel 4 -/+ 1.2 mm.
  const Eigen::Vector3d c1 = g.world_to_index(grid.occupancy.geometry.index_to_world(Eigen::Vector3d(1, 1, 1)));
  EXPECT_NEAR(c1[0], 4.0 - 1.2 / 1.5, 1e-9);
  EXPECT_NEAR(c1[1], 2.0, 1e-9);
}

TEST(OccupancyDownsampling, SeparableFractionsMatchBruteForceAndDominantLabel) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 4; ++trial) {
    ImageGeometry g;
    g.dims = {11 + trial, 9, 7 + trial};
    g.spacing = Eigen::Vector3d(0.8 + 0.1 * trial, 1.1, 1.7 - 0.2 * trial);
    g.direction = Eigen::AngleAxisd(0.3 * trial, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    g.origin = Eigen::Vector3d(5.0 * trial, -3.0, 11.0);
    Volume<uint16_t> mask(g, 0);
    std::uniform_int_distribution<int> pick(0, 2);
    for (auto& v : mask.voxels) v = uint16_t(pick(rng) == 0 ? 0 : 2 + pick(rng) % 2);  // labels 2 and 3
    OccupancyDownsamplingOptions o;
    o.cell_mm = 1.9 + 0.6 * trial;
    o.occupancy_threshold = 0.05;
    const auto grid = downsample_occupancy(mask, o, {});
    const auto& cells = grid.occupancy.geometry;
    EXPECT_TRUE(cells.direction.isApprox(g.direction));
    const auto f2 = tissue_volume_fraction(mask, cells, 2);
    for (int64_t k = 0; k < cells.dims[2]; ++k)
      for (int64_t j = 0; j < cells.dims[1]; ++j)
        for (int64_t i = 0; i < cells.dims[0]; ++i) {
          const double b2 = brute_force_fraction(mask, cells, i, j, k, 2);
          const double b3 = brute_force_fraction(mask, cells, i, j, k, 3);
          ASSERT_NEAR(f2(i, j, k), b2, 1e-9) << trial;
          ASSERT_NEAR(grid.fraction(i, j, k), b2 + b3, 1e-6) << trial;
          const uint16_t dominant = b2 + b3 == 0.0 ? 0 : (b3 > b2 + 1e-12 ? 3 : 2);
          if (std::abs(b2 - b3) > 1e-9) {
            ASSERT_EQ(grid.label(i, j, k), dominant) << trial << " " << i << j << k;
          }
        }
  }
}

TEST(OccupancyDownsampling, LatticeCoversTheMaskWithAnEmptyMargin) {
  const auto mask = ball_mask(Eigen::Vector3d(1.5, 1.5, 1.5), 9.0, 20);
  for (const double h : {1.0, 2.4, 4.0}) {
    OccupancyDownsamplingOptions o;
    o.cell_mm = h;
    const auto grid = downsample_occupancy(mask, o, {});
    const auto& c = grid.occupancy.geometry;
    const auto& d = c.dims;
    // Every tissue voxel centre lies in the inner cells, never in the margin.
    for (int64_t k = 0; k < 20; ++k)
      for (int64_t j = 0; j < 20; ++j)
        for (int64_t i = 0; i < 20; ++i) {
          if (!mask(i, j, k)) continue;
          const Eigen::Vector3d ci = c.world_to_index(mask.geometry.index_to_world(Eigen::Vector3d(double(i), double(j), double(k))));
          for (int a = 0; a < 3; ++a) {
            ASSERT_GE(ci[a], 0.5);
            ASSERT_LE(ci[a], double(d[size_t(a)]) - 1.5);
          }
        }
    for (int64_t k = 0; k < d[2]; ++k)
      for (int64_t j = 0; j < d[1]; ++j)
        for (int64_t i = 0; i < d[0]; ++i) {
          const bool margin = i == 0 || j == 0 || k == 0 || i == d[0] - 1 || j == d[1] - 1 || k == d[2] - 1;
          if (margin) {
            ASSERT_EQ(grid.fraction(i, j, k), 0.0f);
          }
        }
  }
}

TEST(OccupancyDownsampling, MaxDimSetsTheCellSize) {
  const auto mask = ball_mask(Eigen::Vector3d(1.0, 1.0, 1.0), 10.0, 24);
  const IndexBox box = mask_bounding_box(mask);
  const double longest = double(box.hi[0] - box.lo[0] + 1);
  for (const int64_t n : {5, 20, 33}) {
    OccupancyDownsamplingOptions o;
    o.max_dim = n;
    const auto grid = downsample_occupancy(mask, o, {});
    EXPECT_NEAR(grid.occupancy.geometry.spacing[0], longest / double(n), 1e-12);
    EXPECT_EQ(grid.occupancy.geometry.dims[0], n + 2);
  }
}

bool has_18_neighbour(const Volume<uint8_t>& occ, int64_t i, int64_t j, int64_t k) {
  const auto& d = occ.geometry.dims;
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int nz = (dx != 0) + (dy != 0) + (dz != 0);
        if (nz == 0 || nz == 3) continue;
        const int64_t a = i + dx, b = j + dy, c = k + dz;
        if (a >= 0 && b >= 0 && c >= 0 && a < d[0] && b < d[1] && c < d[2] && occ(a, b, c)) return true;
      }
  return false;
}

TEST(OccupancyDownsampling, ParticlesAreThresholdedAndNeverFreeFloating) {
  ImageGeometry g;
  g.dims = {40, 20, 20};
  Volume<uint16_t> mask(g, 0);
  for (int64_t k = 4; k < 16; ++k)
    for (int64_t j = 4; j < 16; ++j)
      for (int64_t i = 2; i < 14; ++i) mask(i, j, k) = 1;  // a 12 mm cube
  for (int64_t k = 6; k < 12; ++k)
    for (int64_t j = 6; j < 12; ++j)
      for (int64_t i = 22; i < 28; ++i) mask(i, j, k) = 1;  // a 6 mm cube, separate
  for (int64_t k = 10; k < 12; ++k)  // a 2 mm speck far away: one full cell, no neighbour
    for (int64_t j = 10; j < 12; ++j)
      for (int64_t i = 34; i < 36; ++i) mask(i, j, k) = 1;
  for (const bool largest : {false, true}) {
    OccupancyDownsamplingOptions o;
    o.cell_mm = 2.0;
    o.keep_largest_only = largest;
    const auto grid = downsample_occupancy(mask, o, {});
    const auto& d = grid.occupancy.geometry.dims;
    int64_t particles = 0;
    for (int64_t k = 0; k < d[2]; ++k)
      for (int64_t j = 0; j < d[1]; ++j)
        for (int64_t i = 0; i < d[0]; ++i) {
          if (!grid.occupancy(i, j, k)) continue;
          ++particles;
          EXPECT_GE(grid.fraction(i, j, k), 0.5f);
          EXPECT_TRUE(has_18_neighbour(grid.occupancy, i, j, k));
        }
    EXPECT_EQ(particles, largest ? 6 * 6 * 6 : 6 * 6 * 6 + 3 * 3 * 3);
  }
}

TEST(OccupancyDownsampling, BadOptionsAreInputErrors) {
  const auto mask = ball_mask(Eigen::Vector3d(1.0, 1.0, 1.0), 5.0, 12);
  auto expect_error = [&](OccupancyDownsamplingOptions o, const std::string& option) {
    try {
      downsample_occupancy(mask, o, {});
      ADD_FAILURE() << "expected InputError for " << option;
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), option) << e.what();
    }
  };
  OccupancyDownsamplingOptions both;
  both.cell_mm = 2.0;
  both.max_dim = 10;
  expect_error(both, "--voxel-mm");
  expect_error(OccupancyDownsamplingOptions{}, "--voxel-mm");
  OccupancyDownsamplingOptions negative;
  negative.cell_mm = -1.0;
  expect_error(negative, "--voxel-mm");
  OccupancyDownsamplingOptions huge;
  huge.cell_mm = 1e-4;  // 1e5 cells per axis: 1e15 cells
  expect_error(huge, "--voxel-mm");
  OccupancyDownsamplingOptions threshold;
  threshold.cell_mm = 2.0;
  threshold.occupancy_threshold = 1.5;
  expect_error(threshold, "--occupancy-threshold");
  Volume<uint16_t> empty(mask.geometry, 0);
  OccupancyDownsamplingOptions ok;
  ok.cell_mm = 2.0;
  EXPECT_THROW(downsample_occupancy(empty, ok, {}), InputError);
}

// The papers' pig heart grid holds 42,745 particles; the whole-heart mask of the sample CT at 2.4 mm
// cells should be of that order, and the fractions conserve the mask volume (669 mL).
TEST(OccupancyDownsamplingRealData, HeartAt2p4mm) {
  CTSURG_REQUIRE_SHARED_DATA();
  const auto labels = read_image_file(test::shared_data_dir() / "heart_cta/heart_mask.nii.gz");
  const auto mask = select_labels(labels, {}, "heart_mask.nii.gz");
  EXPECT_EQ(count_tissue_voxels(mask), 198176);
  OccupancyDownsamplingOptions o;
  o.cell_mm = 2.4;
  const auto grid = downsample_occupancy(mask, o, {{1, "heart"}});
  const double ml = sum(grid.fraction.voxels) * 2.4 * 2.4 * 2.4 / 1000.0;
  EXPECT_NEAR(ml, 198176 * 1.5 * 1.5 * 1.5 / 1000.0, 0.01);
  EXPECT_GT(grid.particle_count(), 42745 * 8 / 10);
  EXPECT_LT(grid.particle_count(), 42745 * 12 / 10);
}

}  // namespace
}  // namespace ctsurg
