// Tests for ctsurg/sim/springs/particle_removal.h and the spring engine's remove primitive (a cautery)
// on a 10 x 3 x 3 bar of 2 mm liver cells (cell centres x = 12 .. 30 mm, y = -18 .. -14, z = 32 .. 36;
// the grid pads it by a cell, so particle_at(10, 2, 2) is the free end's centre):
// the particles inside the tip go nearest first, as far as the volume budget lasts; each takes its
// springs with it (grid: both ends' bits; explicit: the alive flag) and is frozen; the engine spends
// rate x dt a step, counts the volume, opens the surface over the crater and closes it.
#include "ctsurg/sim/springs/particle_removal.h"

#include "block_surface.h"
#include "ctsurg/core/error.h"
#include "ctsurg/sim/base/fixed_regions.h"
#include "ctsurg/sim/springs/spring_calibration.h"
#include "ctsurg/sim/springs/spring_engine.h"
#include "liver_block_engine.h"
#include "sim_test_models.h"
#include "tool_inputs.h"

#include <gtest/gtest.h>

#include <bit>

namespace ctsurg::sim {
namespace {

SpringGridModel liver_bar() {
  const auto occ = test::block_occupancy(10, 3, 3, 2.0);
  return build_spring_grid_model(occ, calibrated_grid_material(material_preset("liver"), occ.geometry));
}

double liver_density() { return material_preset("liver").density; }

TEST(ParticleRemoval, GridTakesTheNearestFirstWhileTheBudgetLastsAndTheirSprings) {
  SpringGridModel m = liver_bar();
  ParticleState state = m.make_state();
  std::vector<uint8_t> removed(static_cast<size_t>(m.particle_count()), 0);
  const int32_t end = m.particle_at(10, 2, 2);  // x = 30: the free end's centre
  const int32_t beside = m.particle_at(9, 2, 2);
  const uint32_t end_springs = m.spring_mask[static_cast<size_t>(end)];
  const Vec3 c{m.rest_positions[3 * static_cast<size_t>(end)] + 0.1, m.rest_positions[3 * static_cast<size_t>(end) + 1],
               m.rest_positions[3 * static_cast<size_t>(end) + 2]};
  // 1.5 cells of budget (a cell is 8 mm^3): the nearest particle only, half a cell left.
  double budget = 12;
  RemovalResult r = remove_particles_in_sphere(m, state, removed, {c, 2.5}, liver_density(), &budget);
  ASSERT_EQ(r.particles.size(), 1u);
  EXPECT_EQ(r.particles[0], end);
  EXPECT_NEAR(r.volume_mm3, 8.0, 1e-5);
  EXPECT_NEAR(budget, 4.0, 1e-5);
  EXPECT_FALSE(r.exhausted);
  EXPECT_EQ(r.springs, std::popcount(end_springs));
  EXPECT_EQ(m.spring_mask[static_cast<size_t>(end)], 0u);
  EXPECT_EQ(removed[static_cast<size_t>(end)], 1);
  EXPECT_EQ(state.inv_mass[static_cast<size_t>(end)], Real(0));
  // Its neighbour lost the spring towards it (direction -x from the end is +x from the neighbour).
  for (int d = 0; d < kGridDirections; ++d) {
    if (m.neighbours[static_cast<size_t>(d) * static_cast<size_t>(m.particle_count()) + static_cast<size_t>(beside)] == end) {
      EXPECT_FALSE(m.spring_mask[static_cast<size_t>(beside)] & (1u << d)) << "direction " << d;
    }
  }
  // Enough budget for everything inside (the end, its -x neighbour and its 4 face neighbours in y and z:
  // 2 mm away; the edge neighbours at 2.83 mm are outside): 5 more, the sphere exhausted.
  budget = 1000;
  r = remove_particles_in_sphere(m, state, removed, {c, 2.5}, liver_density(), &budget);
  EXPECT_EQ(r.particles.size(), 5u);
  EXPECT_TRUE(r.exhausted);
  EXPECT_NEAR(r.volume_mm3, 40.0, 1e-4);
  // Nothing left there: nothing more goes, whatever the budget.
  r = remove_particles_in_sphere(m, state, removed, {c, 2.5}, liver_density(), &budget);
  EXPECT_TRUE(r.particles.empty());
  EXPECT_TRUE(r.exhausted);
}

TEST(ParticleRemoval, ExplicitSpringsLoseTheirAliveFlag) {
  const SpringGridModel grid = liver_bar();
  ExplicitSpringModel m = explicit_model_from_grid(grid);
  ParticleState state = m.make_state();
  std::vector<uint8_t> removed(static_cast<size_t>(m.particle_count()), 0);
  const int32_t end = grid.particle_at(10, 2, 2);
  const int64_t alive = m.alive_spring_count();
  double budget = 8.5;
  const Vec3 c{m.rest_positions[3 * static_cast<size_t>(end)], m.rest_positions[3 * static_cast<size_t>(end) + 1],
               m.rest_positions[3 * static_cast<size_t>(end) + 2]};
  const RemovalResult r = remove_particles_in_sphere(m, state, removed, {c, 2.5}, liver_density(), &budget);
  ASSERT_EQ(r.particles.size(), 1u);
  EXPECT_EQ(r.particles[0], end);
  EXPECT_EQ(r.springs, std::popcount(grid.spring_mask[static_cast<size_t>(end)]));
  EXPECT_EQ(m.alive_spring_count(), alive - r.springs);
  for (int32_t e = m.row_offsets[static_cast<size_t>(end)]; e < m.row_offsets[static_cast<size_t>(end) + 1]; ++e) {
    EXPECT_EQ(m.alive[static_cast<size_t>(m.row_spring[static_cast<size_t>(e)])], 0);
  }
}

TEST(ParticleRemoval, BadInputIsRefused) {
  SpringGridModel m = liver_bar();
  ParticleState state = m.make_state();
  std::vector<uint8_t> removed(3, 0);
  double budget = 10;
  EXPECT_THROW(remove_particles_in_sphere(m, state, removed, {{30, -16, 34}, 2}, liver_density(), &budget), InputError);
  removed.assign(static_cast<size_t>(m.particle_count()), 0);
  EXPECT_THROW(remove_particles_in_sphere(m, state, removed, {{30, -16, 34}, 2}, 0.0, &budget), InputError);
}

// The bar fixed at its x = 12 end, with its surface (close_cuts on).
SpringEngine removal_bar_engine() { return test::liver_block_engine(10, 3, 3, 12.5); }

ToolInput spring_cautery(const Vec3& centre, double rate, bool active = true) { return test::cautery_input(centre, 2.5, rate, active); }

TEST(SpringEngineCautery, RemovesAtItsRateCountsTheVolumeAndClosesTheCrater) {
  SpringEngine e = removal_bar_engine();
  const size_t triangles = e.triangles().size();
  const auto& model = std::get<SpringGridModel>(e.model());
  const int32_t end = model.particle_at(10, 2, 2);
  // 0.3 of a cell (8 mm^3) a step: the first particle after 4 steps, three after 11 (3.3 cells).
  const double rate = 0.3 * 8.0 / e.dt();
  const ToolInput tip = spring_cautery({30.1, -16, 34}, rate);
  ASSERT_TRUE(e.step({tip}, 3).stable);
  EXPECT_EQ(e.metrics().removed_volume, 0.0);
  ASSERT_TRUE(e.step({tip}, 1).stable);
  EXPECT_NEAR(e.metrics().removed_volume, 8.0, 1e-4);
  EXPECT_EQ(e.state().inv_mass[static_cast<size_t>(end)], Real(0));  // the nearest went first
  ASSERT_TRUE(e.step({tip}, 7).stable);
  EXPECT_NEAR(e.metrics().removed_volume, 24.0, 1e-4);
  // The surface over the removed cells is gone and the crater is closed over (close_cuts).
  const EngineMetrics m = e.metrics();
  EXPECT_GT(m.triangles_removed, 0);
  EXPECT_GT(e.closing_triangles(), 0);
  EXPECT_GT(m.springs_cut, 0);
  EXPECT_NE(e.triangles().size(), triangles);
  // Off: nothing more goes, and the budget does not carry over to the next touch.
  ASSERT_TRUE(e.step({spring_cautery({30.1, -16, 34}, rate, false)}, 20).stable);
  EXPECT_NEAR(e.metrics().removed_volume, 24.0, 1e-4);
  ASSERT_TRUE(e.step({tip}, 3).stable);
  EXPECT_NEAR(e.metrics().removed_volume, 24.0, 1e-4);
  EXPECT_TRUE(e.check_stability().stable);
}

TEST(SpringEngineCautery, RestartGivesBackWhatWasRemoved) {
  SpringEngine e = removal_bar_engine();
  const double rate = 2.2 * 8.0 / e.dt();  // 2.2 cells a step: two go
  e.save_checkpoint();
  ASSERT_TRUE(e.step({spring_cautery({30.1, -16, 34}, rate)}, 1).stable);
  EXPECT_NEAR(e.metrics().removed_volume, 16.0, 1e-4);
  e.restart_halved();
  EXPECT_EQ(e.metrics().removed_volume, 0.0);
  const auto& model = std::get<SpringGridModel>(e.model());
  EXPECT_NE(model.spring_mask[static_cast<size_t>(model.particle_at(10, 2, 2))], 0u);
  // Half the step: 1.1 cells a step now, one goes.
  ASSERT_TRUE(e.step({spring_cautery({30.1, -16, 34}, rate)}, 1).stable);
  EXPECT_NEAR(e.metrics().removed_volume, 8.0, 1e-4);
}

TEST(SpringEngineCautery, WithoutTheTissuesDensityItIsRefused) {
  SpringGridModel model = liver_bar();
  ParticleState state = model.make_state();
  EngineOptions o;
  o.where = "s.yaml";
  SpringEngine e(std::move(model), std::move(state), EmbeddedSurface(), {0, 0, 0}, o);
  try {
    (void)e.step({spring_cautery({30, -16, 34}, 100)}, 1);
    ADD_FAILURE() << "a cautery without the density was accepted";
  } catch (const InputError& err) {
    EXPECT_EQ(err.field(), "tools[0] (cautery)");
  }
}

}  // namespace
}  // namespace ctsurg::sim
