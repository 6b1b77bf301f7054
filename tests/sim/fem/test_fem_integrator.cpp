// Tests for ctsurg/sim/fem/fem_integrator.h on the 8 x 2 x 2 mm bar of Kuhn tets fixed at x = 0:
// make_fem_integrator picks the integrator the solver names; a dynamic integrator handed its own
// carried state (a cut or a removal rebuilds it on the new mesh) continues as if it had not been rebuilt
// (the explicit one bit for bit, the implicit one within its Newton tolerance); the static one carries
// its time; each refuses what it is not (a static advance, a
// dynamic equilibrium); a quasi-Newton static drag, extrapolated frame to frame, matches Newton's.
#include "ctsurg/sim/fem/fem_integrator.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/fem/fem_engine.h"
#include "fem_test_models.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace ctsurg::sim {
namespace {

const std::array<int, 3> kIntegratorCells{8, 2, 2};
const std::array<double, 3> kIntegratorSize{8, 2, 2};

// A grab of the free end moving +x at 10 mm/s.
ToolInput integrator_grab(double t) {
  ToolInput g;
  g.acts = ToolPrimitive::hold;
  g.label = "tools[0] (grab)";
  g.radius_mm = 1.01;
  g.active = true;
  g.centre = {8 + 10 * t, 1, 1};
  g.start_centre = {8, 1, 1};
  return g;
}

FemEngineOptions integrator_options(FemSolver solver) {
  FemEngineOptions o;
  o.solver = solver;
  o.where = "s.yaml";
  o.mass_damping = 5;
  o.dt = solver == FemSolver::implicit ? 1e-3 : 0;
  return o;
}

// The Neo-Hookean bar, its end at x = 0 fixed, and the tools' holds over it.
struct IntegratorBar {
  FemModel model = test::fem_box_model(FemLaw::neo_hookean, kIntegratorCells, kIntegratorSize);
  FemBoundaryConditions supports{test::nodes_where(model, 0, 0.0), {}, {}, {}};
  FemToolHolds holds{model, held_axes(), "s.yaml"};
  std::vector<uint8_t> held_axes() const {
    std::vector<uint8_t> held(static_cast<size_t>(model.node_count()), 0);
    for (const int32_t n : supports.fixed_nodes) held[static_cast<size_t>(n)] = kAllAxes;
    return held;
  }
};

// Steps `total` steps of the dynamic integrator for `solver`, rebuilding it after `rebuild_at` steps
// with its carried state (rebuild_at = 0: never); the displacements at the end.
std::vector<double> stepped(FemSolver solver, int total, int rebuild_at) {
  IntegratorBar bar;
  const FemModel& model = bar.model;
  const FemBoundaryConditions& supports = bar.supports;
  FemToolHolds& holds = bar.holds;
  const FemEngineOptions o = integrator_options(solver);
  std::unique_ptr<FemIntegrator> integrator = make_fem_integrator(model, supports, o, Backend::cpu);
  std::vector<double> u(model.nodes.size(), 0.0);
  for (int k = 0; k < total; ++k) {
    if (k == rebuild_at && rebuild_at > 0) {
      integrator->displacements(u);
      const FemCarriedState carried = integrator->carried_state();
      integrator = make_fem_integrator(model, supports, o, Backend::cpu);
      integrator->restore(carried, u, holds.nodal_forces());
    }
    const FemAdvance a = integrator->advance(holds, {integrator_grab(integrator->time() + integrator->dt())}, 1, u);
    EXPECT_TRUE(a.stability.stable) << a.stability.message;
  }
  integrator->displacements(u);
  return u;
}

TEST(FemIntegrator, TheSolverNamesTheIntegrator) {
  const FemModel model = test::fem_box_model(FemLaw::linear, kIntegratorCells, kIntegratorSize);
  FemBoundaryConditions supports;
  supports.fixed_nodes = test::nodes_where(model, 0, 0.0);
  const auto dynamic = make_fem_integrator(model, supports, integrator_options(FemSolver::dynamic), Backend::cpu);
  EXPECT_FALSE(dynamic->quasi_static());
  EXPECT_GT(dynamic->dt(), 0);
  EXPECT_EQ(dynamic->local_region(), nullptr);
  const auto implicit = make_fem_integrator(model, supports, integrator_options(FemSolver::implicit), Backend::cpu);
  EXPECT_FALSE(implicit->quasi_static());
  EXPECT_EQ(implicit->dt(), 1e-3);
  EXPECT_EQ(implicit->contact(), nullptr);
  const auto quasi = make_fem_integrator(model, supports, integrator_options(FemSolver::static_equilibrium), Backend::cpu);
  EXPECT_TRUE(quasi->quasi_static());
  EXPECT_EQ(quasi->dt(), 0);
  // Each refuses what it is not.
  std::vector<uint8_t> held(static_cast<size_t>(model.node_count()), 0);
  FemToolHolds holds(model, held, "s.yaml");
  std::vector<double> u(model.nodes.size(), 0.0);
  EXPECT_THROW(quasi->advance(holds, {}, 1, u), RuntimeError);
  EXPECT_THROW(dynamic->equilibrium(holds, {}, 0.1, false, u), RuntimeError);
  // The static sequence needs supports.
  EXPECT_THROW(make_fem_integrator(model, {}, integrator_options(FemSolver::static_equilibrium), Backend::cpu), InputError);
}

TEST(FemIntegrator, ARebuiltDynamicIntegratorContinuesWhereItWas) {
  for (const FemSolver solver : {FemSolver::dynamic, FemSolver::implicit}) {
    const std::vector<double> straight = stepped(solver, 40, 0);
    const std::vector<double> rebuilt = stepped(solver, 40, 17);
    ASSERT_EQ(straight.size(), rebuilt.size());
    double moved = 0, worst = 0;
    for (size_t i = 0; i < straight.size(); ++i) {
      if (solver == FemSolver::dynamic) {
        EXPECT_EQ(straight[i], rebuilt[i]) << "value " << i;
      }
      moved = std::max(moved, std::abs(straight[i]));
      worst = std::max(worst, std::abs(straight[i] - rebuilt[i]));
    }
    EXPECT_GT(moved, 1e-3) << "the grab moved the bar";
    // Backward Euler keeps its factorised tangent across steps; rebuilt, it factorises afresh at the
    // carried state, so its Newton steps round differently, within its tolerance.
    if (solver == FemSolver::implicit) {
      EXPECT_LT(worst, 1e-5 * moved) << "worst " << worst;  // measured 1.6e-6 of it
    }
    std::printf("solver %d: rebuilt after 17 of 40 steps, worst difference %.3g mm of %.3g\n", static_cast<int>(solver), worst, moved);
  }
}

TEST(FemIntegrator, TheStaticSequenceSolvesFramesAndCarriesItsTime) {
  IntegratorBar bar;
  const FemModel& model = bar.model;
  const FemBoundaryConditions& supports = bar.supports;
  FemToolHolds& holds = bar.holds;
  const FemEngineOptions o = integrator_options(FemSolver::static_equilibrium);
  auto quasi = make_fem_integrator(model, supports, o, Backend::cpu);
  std::vector<double> u(model.nodes.size(), 0.0);
  const FemAdvance a = quasi->equilibrium(holds, {integrator_grab(0.1)}, 0.1, false, u);
  EXPECT_GT(a.newton_iterations, 0);
  EXPECT_EQ(quasi->time(), 0.1);
  double tip = 0;
  for (int32_t n = 0; n < model.node_count(); ++n)
    if (model.nodes[3 * static_cast<size_t>(n)] == 8.0) tip = std::max(tip, u[3 * static_cast<size_t>(n)]);
  EXPECT_NEAR(tip, 1.0, 1e-9);  // the grabbed end where the tool put it
  EXPECT_GT(quasi->strain_energy(model, u), 0);
  const FemCarriedState carried = quasi->carried_state();
  auto rebuilt = make_fem_integrator(model, supports, o, Backend::cpu);
  rebuilt->restore(carried, u, holds.nodal_forces());
  EXPECT_EQ(rebuilt->time(), 0.1);
}

// A drag of the bar's end (0.1 mm a frame, 20 frames: a quarter of its length) as a static sequence: quasi-Newton, which starts
// each frame from the last two frames' extrapolation while the grab holds the same nodes, against
// Newton; the same equilibria to a few budgets, and fewer nonlinear iterations than without the
// extrapolation would need (the first frames after the grab's begin are not extrapolated).
TEST(FemIntegrator, AQuasiNewtonDragStartsFromTheExtrapolatedFramesAndMatchesNewton) {
  IntegratorBar bar;
  FemEngineOptions o = integrator_options(FemSolver::static_equilibrium);
  o.newton.tolerance_mm = 1e-3;
  FemEngineOptions q = o;
  q.newton.nonlinear = FemNonlinearSolve::quasi_newton;
  auto newton = make_fem_integrator(bar.model, bar.supports, o, Backend::cpu);
  auto quasi = make_fem_integrator(bar.model, bar.supports, q, Backend::cpu);
  FemToolHolds quasi_holds{bar.model, bar.held_axes(), "s.yaml"};
  std::vector<double> un(bar.model.nodes.size(), 0.0), uq = un;
  int first = 0, later = 0;
  for (int k = 1; k <= 20; ++k) {
    const double t = 0.01 * k;
    newton->equilibrium(bar.holds, {integrator_grab(t)}, t, k > 1, un);
    const FemAdvance a = quasi->equilibrium(quasi_holds, {integrator_grab(t)}, t, k > 1, uq);
    (k <= 3 ? first : later) += a.newton_iterations;
    EXPECT_LT(test::max_abs_difference(un, uq), 5e-3) << "frame " << k;
  }
  // Once extrapolated, a frame of the steady drag takes fewer iterations than the first ones.
  std::printf("quasi-Newton drag: %.2f iterations a frame in frames 1-3, %.2f in frames 4-20\n", first / 3.0, later / 17.0);
  EXPECT_LT(later / 17.0, first / 3.0);
}

}  // namespace
}  // namespace ctsurg::sim
