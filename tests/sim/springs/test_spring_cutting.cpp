#include "ctsurg/sim/springs/spring_cutting.h"

#include "ctsurg/sim/springs/spring_mass_step.h"
#include "ctsurg/sim/springs/stability.h"
#include "sim_test_models.h"

#include <gtest/gtest.h>

namespace ctsurg::sim {
namespace {

using test::block_occupancy;
using test::test_material;

// Two triangles covering the horizontal plane z = z0 over the square [x0, x1] x [y0, y1].
std::array<Triangle, 2> horizontal_blade(double z0, double x0, double x1, double y0, double y1) {
  return {Triangle{{x0, y0, z0}, {x1, y0, z0}, {x1, y1, z0}}, Triangle{{x0, y0, z0}, {x1, y1, z0}, {x0, y1, z0}}};
}

TEST(SpringCutting, APlaneCutsExactlyTheSpringsCrossingItOnBothEnds) {
  // 3 x 3 x 10 bar, 2 mm cells; levels z = 32 .. 50. The plane z = 41 lies between levels 5 and 6.
  auto model = build_spring_grid_model(block_occupancy(3, 3, 10, 2.0), test_material());
  const auto state = model.make_state();
  const int64_t before = model.spring_count();
  int64_t cut = 0;
  for (const auto& t : horizontal_blade(41, 0, 30, -40, 0)) cut += cut_springs_crossing_triangle(model, state, t);
  EXPECT_EQ(cut, 9 + 24);  // 9 face springs along z, 2 x 2 x 3 x 2 diagonal ones
  EXPECT_EQ(model.spring_count(), before - cut);
  const int64_t n = model.particle_count();
  for (int32_t i = 0; i < n; ++i)
    for (int d = 0; d < kGridDirections; ++d) {
      const int32_t j = model.neighbours[d * n + i];
      if (j < 0) continue;
      const bool crosses = (model.rest_positions[3 * i + 2] - 41) * (model.rest_positions[3 * j + 2] - 41) < 0;
      EXPECT_EQ(model.spring_mask[i] >> d & 1u, crosses ? 0u : 1u);
      EXPECT_EQ(model.spring_mask[i] >> d & 1u, model.spring_mask[j] >> opposite_direction(d) & 1u);
    }
  // A second pass over the same blade finds nothing left to cut; a blade beside the bar cuts nothing.
  for (const auto& t : horizontal_blade(41, 0, 30, -40, 0)) EXPECT_EQ(cut_springs_crossing_triangle(model, state, t), 0);
  for (const auto& t : horizontal_blade(45, 100, 130, -40, 0)) EXPECT_EQ(cut_springs_crossing_triangle(model, state, t), 0);
}

TEST(SpringCutting, AHalfBladeCutsHalfAndTheExplicitModelAgrees) {
  auto grid = build_spring_grid_model(block_occupancy(4, 4, 4, 2.0), test_material());
  auto expl = explicit_model_from_grid(grid);
  const auto s = grid.make_state();
  // Covers x < 15 only: particles at x = 12, 14 on both sides of z = 35 (between z = 34 and 36).
  int64_t grid_cut = 0, expl_cut = 0;
  for (const auto& t : horizontal_blade(35, 0, 15, -40, 0)) {
    grid_cut += cut_springs_crossing_triangle(grid, s, t);
    expl_cut += cut_springs_crossing_triangle(expl, s, t);
  }
  EXPECT_GT(grid_cut, 0);
  EXPECT_EQ(grid_cut, expl_cut);
  EXPECT_EQ(grid.spring_count(), expl.alive_spring_count());
  // The explicit model's CPU layout follows the cut: no entry of a cut spring is present.
  for (int32_t sp = 0; sp < expl.spring_count(); ++sp)
    for (int end = 0; end < 2; ++end) {
      const int64_t at = expl.spring_entries[2 * sp + end];
      if (at >= 0) {
        EXPECT_EQ(expl.ell_present[at], expl.alive[sp] ? 1 : 0);
      }
    }
  const Triangle degenerate{{0, 0, 35}, {30, 0, 35}, {60, 0, 35}};
  EXPECT_EQ(cut_springs_crossing_triangle(grid, s, degenerate), 0);
}

TEST(SpringCutting, ABarCutByABladeSeparates) {
  auto model = build_spring_grid_model(block_occupancy(3, 3, 10, 2.0), test_material(2e4, 1e4));
  auto s = model.make_state();
  for (int32_t i = 0; i < s.count(); ++i)
    if (model.rest_positions[3 * i + 2] > 49) s.set_fixed(i, true);  // top layer
  StepParameters p;
  p.dt = critical_time_step(model).dt;
  p.gravity = {0, 0, -9810};
  for (int n = 0; n < 200; ++n) step(model, s, p);
  for (const auto& t : horizontal_blade(41, 0, 30, -40, 0)) cut_springs_crossing_triangle(model, s, t);
  for (int n = 0; n < 2000; ++n) step(model, s, p);
  // The lower piece has fallen away from the upper one: the gap between levels 5 and 6 opened by
  // far more than a spring's elongation.
  const int32_t above = model.particle_at(2, 2, 6), below = model.particle_at(2, 2, 5);
  EXPECT_GT(s.z[above] - s.z[below], 2.0 + 5.0);
}

}  // namespace
}  // namespace ctsurg::sim
