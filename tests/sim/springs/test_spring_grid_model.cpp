#include "ctsurg/sim/springs/spring_grid_model.h"

#include "ctsurg/core/error.h"
#include "sim_test_models.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ctsurg::sim {
namespace {

using test::block_occupancy;
using test::test_material;

// Springs of an a x b x c block: face springs along each axis, and two edge springs per unit square
// of each axis plane.
int64_t block_springs(int64_t a, int64_t b, int64_t c) {
  const int64_t face = (a - 1) * b * c + a * (b - 1) * c + a * b * (c - 1);
  const int64_t edge = 2 * ((a - 1) * (b - 1) * c + (a - 1) * b * (c - 1) + a * (b - 1) * (c - 1));
  return face + edge;
}

TEST(SpringGridModel, BlockHasAnalyticCountsRestLengthsAndMasses) {
  for (auto [a, b, c] : {std::array{1, 1, 5}, std::array{3, 4, 5}, std::array{6, 2, 7}}) {
    const double h = 2.5;
    const auto model = build_spring_grid_model(block_occupancy(a, b, c, h), test_material());
    EXPECT_EQ(model.particle_count(), a * b * c);
    EXPECT_EQ(model.spring_count(), block_springs(a, b, c)) << a << "x" << b << "x" << c;
    for (int d = 0; d < kGridDirections; ++d)
      EXPECT_NEAR(model.rest_length[d], is_face_direction(d) ? h : h * std::sqrt(2.0), 1e-6);
    for (Real m : model.mass) EXPECT_NEAR(m, 1e-3 * h * h * h, 1e-9);
  }
}

TEST(SpringGridModel, RestPositionsAreCellCentresAndEmptyCellsAreNotParticles) {
  auto occ = block_occupancy(4, 3, 2, 2.0);
  occ(2, 2, 1) = 0;  // a hole inside the block (margin 1: block cell (1, 1, 0))
  const auto model = build_spring_grid_model(occ, test_material());
  ASSERT_EQ(model.particle_count(), 23);
  EXPECT_EQ(model.particle_at(2, 2, 1), -1);
  EXPECT_EQ(model.particle_at(0, 0, 0), -1);   // margin
  EXPECT_EQ(model.particle_at(-1, 0, 0), -1);  // outside
  const int32_t p = model.particle_at(3, 2, 1);
  ASSERT_GE(p, 0);
  EXPECT_FLOAT_EQ(model.rest_positions[3 * p], 10 + 3 * 2.0);
  EXPECT_FLOAT_EQ(model.rest_positions[3 * p + 1], -20 + 2 * 2.0);
  EXPECT_FLOAT_EQ(model.rest_positions[3 * p + 2], 30 + 1 * 2.0);
  // The -x neighbour of (3, 2, 1) is the hole: no neighbour, no spring.
  EXPECT_EQ(model.neighbours[1 * model.particle_count() + p], -1);
  EXPECT_EQ(model.spring_mask[p] >> 1 & 1u, 0u);
  for (std::size_t i = 1; i < model.cells.size(); ++i) EXPECT_LT(model.cells[i - 1], model.cells[i]);
}

TEST(SpringGridModel, MasksAreSymmetricAndNeighboursMatchOffsets) {
  auto occ = block_occupancy(5, 4, 3, 1.0);
  occ(1, 1, 1) = 0, occ(3, 2, 2) = 0, occ(5, 4, 3) = 0;
  const auto model = build_spring_grid_model(occ, test_material());
  const int64_t n = model.particle_count();
  const auto& dims = model.lattice.dims;
  for (int64_t p = 0; p < n; ++p) {
    const int64_t c = model.cells[p];
    const int64_t i = c % dims[0], j = c / dims[0] % dims[1], k = c / (dims[0] * dims[1]);
    for (int d = 0; d < kGridDirections; ++d) {
      const auto& o = kGridDirectionOffsets[d];
      const int32_t q = model.neighbours[d * n + p];
      EXPECT_EQ(q, model.particle_at(i + o[0], j + o[1], k + o[2]));
      const bool bit = model.spring_mask[p] >> d & 1u;
      EXPECT_EQ(bit, q >= 0);
      if (q >= 0) {
        EXPECT_EQ(model.spring_mask[q] >> opposite_direction(d) & 1u, 1u);
      }
    }
  }
}

TEST(SpringGridModel, CuttingASpringClearsBothEnds) {
  auto model = build_spring_grid_model(block_occupancy(3, 3, 3, 1.0), test_material());
  const int64_t before = model.spring_count();
  const int32_t centre = model.particle_at(2, 2, 2);
  const int d = 10;  // (+1, 0, +1)
  const int32_t other = model.neighbours[d * model.particle_count() + centre];
  ASSERT_TRUE(cut_grid_spring(model, centre, d));
  EXPECT_EQ(model.spring_mask[centre] >> d & 1u, 0u);
  EXPECT_EQ(model.spring_mask[other] >> opposite_direction(d) & 1u, 0u);
  EXPECT_EQ(model.spring_count(), before - 1);
  EXPECT_FALSE(cut_grid_spring(model, other, opposite_direction(d)));  // already cut from the other end
  EXPECT_THROW(cut_grid_spring(model, centre, 18), InputError);
}

TEST(SpringGridModel, MassFromFraction) {
  const auto occ = block_occupancy(2, 2, 2, 2.0);
  Volume<float> fraction(occ.geometry, 0.f);
  fraction(1, 1, 1) = 0.5f;
  fraction(2, 1, 1) = 1.0f;
  auto material = test_material();
  material.mass_from_fraction = true;
  const auto model = build_spring_grid_model(occ, material, &fraction);
  EXPECT_NEAR(model.mass[model.particle_at(1, 1, 1)], 0.5 * 8e-3, 1e-9);
  EXPECT_NEAR(model.mass[model.particle_at(2, 1, 1)], 8e-3, 1e-9);
  EXPECT_GT(model.mass[model.particle_at(1, 2, 1)], 0);  // fraction 0 still gets a small positive mass
  EXPECT_THROW(build_spring_grid_model(occ, material, nullptr), InputError);
}

TEST(SpringGridModel, RejectsBadInput) {
  const auto occ = block_occupancy(2, 2, 2, 1.0);
  EXPECT_THROW(build_spring_grid_model(Volume<uint8_t>(occ.geometry, 0), test_material()), InputError);
  EXPECT_THROW(build_spring_grid_model(occ, test_material(0, 10)), InputError);
  EXPECT_THROW(build_spring_grid_model(occ, test_material(10, -1)), InputError);
  auto m = test_material();
  m.density = 0;
  EXPECT_THROW(build_spring_grid_model(occ, m), InputError);
}

TEST(SpringGridModel, AnisotropicLatticeRestLengthsFollowTheLatticeMatrix) {
  auto occ = block_occupancy(2, 2, 2, 1.0);
  occ.geometry.spacing = Eigen::Vector3d(1.0, 2.0, 3.0);
  const auto model = build_spring_grid_model(occ, test_material());
  EXPECT_NEAR(model.rest_length[0], 1.0, 1e-6);
  EXPECT_NEAR(model.rest_length[2], 2.0, 1e-6);
  EXPECT_NEAR(model.rest_length[4], 3.0, 1e-6);
  EXPECT_NEAR(model.rest_length[14], std::sqrt(13.0), 1e-6);  // (0, 1, 1)
}

}  // namespace
}  // namespace ctsurg::sim
