#include "ctsurg/sim/springs/stability.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/springs/spring_mass_step.h"
#include "sim_test_models.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ctsurg::sim {
namespace {

using test::block_occupancy;
using test::perturb;
using test::test_material;

TEST(Stability, CriticalStepOfTheStiffestParticle) {
  // Two unit masses and a 3 g mass on a chain of springs 100 and 400 g/s^2: particle 1 has K = 500.
  const std::vector<Real> rest{0, 0, 0, 1, 0, 0, 2, 0, 0};
  const auto model = build_explicit_spring_model(rest, {1, 1, 3}, {{0, 1, 100, 1, 0}, {1, 2, 400, 1, 0}});
  const auto c = critical_time_step(model);
  EXPECT_EQ(c.particle, 1);
  EXPECT_NEAR(c.critical, 2 * std::sqrt(1.0 / 500.0), 1e-12);
  EXPECT_NEAR(c.dt, 0.5 * c.critical, 1e-15);
  EXPECT_THROW(critical_time_step(model, 0), InputError);
  // Grid: interior particle of a block has 6 face + 12 edge springs.
  const auto grid = build_spring_grid_model(block_occupancy(3, 3, 3, 2.0), test_material(1000, 500));
  const auto g = critical_time_step(grid, 0.25);
  EXPECT_NEAR(g.stiffness_sum, 6 * 1000 + 12 * 500, 1e-9);
  EXPECT_NEAR(g.critical, 2 * std::sqrt(8e-3 / 12000.0), 1e-9);
  EXPECT_NEAR(g.dt, 0.25 * g.critical, 1e-12);
}

TEST(Stability, GuardStopsAnUnstableRunBeforeItHoldsNaN) {
  const auto model = build_spring_grid_model(block_occupancy(5, 5, 5, 2.0), test_material(1000, 500));
  const double dt_crit = critical_time_step(model).critical;
  for (double factor : {0.5, 2.0}) {
    auto s = model.make_state();
    perturb(s, 0.05);
    StepParameters p;
    p.dt = factor * dt_crit;
    auto guard = make_stability_guard(model, p.dt);
    StabilityReport report;
    int steps = 0;
    for (; steps < 5000 && report.stable; ++steps) {
      step(model, s, p);
      report = guard.check(s, (steps + 1) * p.dt);
    }
    if (factor < 1) {
      EXPECT_TRUE(report.stable) << report.message;
    } else {
      ASSERT_FALSE(report.stable) << "2 dt_crit ran " << steps << " steps";
      EXPECT_GE(report.particle, 0);
      EXPECT_NE(report.message.find("unstable at t = "), std::string::npos) << report.message;
      EXPECT_NE(report.message.find("try a smaller time step"), std::string::npos);
      for (int32_t i = 0; i < s.count(); ++i) ASSERT_TRUE(std::isfinite(s.x[i]) && std::isfinite(s.y[i]) && std::isfinite(s.z[i]));
      EXPECT_THROW(guard.enforce(s, steps * p.dt), RuntimeError);
    }
  }
}

TEST(Stability, GuardNamesNonFinitePositions) {
  const auto model = build_spring_grid_model(block_occupancy(2, 2, 2, 1.0), test_material());
  auto s = model.make_state();
  auto guard = make_stability_guard(model, 1e-4);
  EXPECT_TRUE(guard.check(s, 0).stable);
  s.y[5] = std::nanf("");
  const auto r = guard.check(s, 0.25);
  EXPECT_FALSE(r.stable);
  EXPECT_EQ(r.particle, 5);
  EXPECT_NE(r.message.find("non-finite"), std::string::npos) << r.message;
}

TEST(Stability, EnergiesAndMomentum) {
  const std::vector<Real> rest{0, 0, 0, 2, 0, 0};
  const auto model = build_explicit_spring_model(rest, {2, 3}, {{0, 1, 10, 1.5, 0}});
  auto s = model.make_state();
  EXPECT_NEAR(spring_energy(model, s), 0.5 * 10 * 0.25, 1e-6);
  s.set_velocity(0, 1, 0, 0, 0.01);
  s.set_velocity(1, 0, 2, 0, 0.01);
  EXPECT_NEAR(kinetic_energy(s, 0.01), 0.5 * 2 * 1 + 0.5 * 3 * 4, 1e-3);
  const auto p = momentum(s, 0.01);
  EXPECT_NEAR(p[0], 2, 1e-4);
  EXPECT_NEAR(p[1], 6, 1e-4);
}

}  // namespace
}  // namespace ctsurg::sim

TEST(Stability, AFreelyFallingPieceIsNotUnstable) {
  // A particle cut free falls: after 1 s under 9810 mm/s^2 it moves g t dt = 4.9 mm per 0.5 ms step,
  // far more than half a 2.4 mm spring. With the run's gravity the guard allows it; without, it flags it;
  // and a move beyond free fall is still flagged with gravity.
  const double dt = 5e-4, g = 9810;
  const std::vector<ctsurg::sim::Real> rest = {0, 0, 0};
  ctsurg::sim::ParticleState s(rest, {1.0f});
  s.z[0] = -4900.0f;
  s.pz[0] = static_cast<ctsurg::sim::Real>(-4900.0 + g * 1.0 * dt);
  ctsurg::sim::StabilityGuardOptions with_g;
  with_g.gravity = g;
  ctsurg::sim::StabilityGuard falling(rest, 2.4, dt, with_g), plain(rest, 2.4, dt);
  EXPECT_TRUE(falling.check(s, 1.0).stable);
  EXPECT_FALSE(plain.check(s, 1.0).stable);
  s.pz[0] = static_cast<ctsurg::sim::Real>(-4900.0 + 2 * g * 1.0 * dt);
  EXPECT_FALSE(falling.check(s, 1.0).stable);
}
