#include "ctsurg/sim/base/fixed_regions.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/springs/spring_mass_step.h"
#include "sim_test_models.h"

#include <gtest/gtest.h>

namespace ctsurg::sim {
namespace {

using test::block_occupancy;
using test::test_material;

TEST(FixedRegions, BoxHalfSpaceAndLabelSelectByRestPosition) {
  // 3 x 3 x 4 block, 2 mm cells, origin (10, -20, 30), margin 1: particle centres x in {12, 14, 16},
  // z in {32, 34, 36, 38}.
  const auto occ = block_occupancy(3, 3, 4, 2.0);
  const auto model = build_spring_grid_model(occ, test_material());
  const auto box = particles_in_box(model.rest_positions, {{11, -100, 31}, {14, 100, 34}});
  EXPECT_EQ(box.size(), 2u * 3 * 2);  // x in {12, 14}, all y, z in {32, 34}
  const auto top = particles_in_half_space(model.rest_positions, {{0, 0, 37}, {0, 0, 2}});
  EXPECT_EQ(top.size(), 9u);
  for (int32_t p : top) EXPECT_FLOAT_EQ(model.rest_positions[3 * p + 2], 38);
  Volume<uint16_t> label(occ.geometry, 0);
  label(2, 2, 2) = 7, label(3, 3, 4) = 7, label(0, 0, 0) = 7;  // two particles' cells and a margin cell
  const auto labelled = particles_with_label(model, label, 7);
  ASSERT_EQ(labelled.size(), 2u);
  EXPECT_EQ(labelled[0], model.particle_at(2, 2, 2));
  EXPECT_EQ(labelled[1], model.particle_at(3, 3, 4));
  EXPECT_THROW(particles_in_box(model.rest_positions, {{1, 1, 1}, {0, 2, 2}}), InputError);
  EXPECT_THROW(particles_in_half_space(model.rest_positions, {{0, 0, 0}, {0, 0, 0}}), InputError);
  Volume<uint16_t> other(occ.geometry, 0);
  other.geometry.origin[0] += 1;
  EXPECT_THROW(particles_with_label(model, other, 7), InputError);
}

TEST(FixedRegions, FixedParticlesDoNotMoveUnderGravity) {
  const auto model = build_spring_grid_model(block_occupancy(3, 3, 4, 2.0), test_material(2000, 1000));
  auto s = model.make_state();
  const auto top = particles_in_half_space(model.rest_positions, {{0, 0, 37}, {0, 0, 1}});
  fix_particles(s, top);
  StepParameters p;
  p.dt = 1e-4;
  p.gravity = {0, 0, -9810};
  for (int n = 0; n < 500; ++n) step(model, s, p);
  for (int32_t q : top) EXPECT_EQ(s.z[q], model.rest_positions[3 * q + 2]);
  EXPECT_LT(s.z[0], model.rest_positions[2]);  // the free bottom sags
  EXPECT_THROW(fix_particles(s, {s.count()}), InputError);
}

}  // namespace
}  // namespace ctsurg::sim
