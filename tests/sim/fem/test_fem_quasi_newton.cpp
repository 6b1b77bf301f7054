// Tests of the quasi-Newton iteration (FemNonlinearSolve::quasi_newton, fem_static_solver.h;
// src/fem_quasi_newton.cpp): it reaches Newton's solution to its millimetre budget on every law, under a
// large grab and under gravity; a quasi-static sequence factorises the rest stiffness once and keeps it
// across frames; a held set that changes refactorises;
// out-of-range options are refused by name; and with too few iterations allowed it goes on with Newton.
#include "ctsurg/sim/fem/fem_static_solver.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/fem/fem_implicit_dynamics.h"
#include "fem_test_models.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace ctsurg::sim {
namespace {

using test::fem_box_model;
using test::max_abs_difference;
using test::nodes_where;

// A 10 x 10 x 30 mm column, its base held; its top moved by `pull` (mm) as a grab.
struct GrabbedColumn {
  FemModel model;
  FemBoundaryConditions bc;
};

GrabbedColumn grabbed_column(FemLaw law, const std::array<double, 3>& pull) {
  const auto box = fem_box_mesh({3, 3, 9}, {10, 10, 30});
  // Mooney-Rivlin's constants set its stiffness: c10 + c01 = E / (4 (1 + nu)) as the others' 30 kPa.
  const FemMaterial material = law == FemLaw::mooney_rivlin ? fem_material_from_constants(law, {3500, 1672}, 0.45, 1.06e-3)
                                                            : test::fem_material(law, 3e4, 0.45);
  GrabbedColumn c{build_fem_model(box.nodes, box.tets, material), {}};
  c.bc.fixed_nodes = nodes_where(c.model, 2, 0);
  c.bc.prescribed_nodes = nodes_where(c.model, 2, 30);
  for (size_t k = 0; k < c.bc.prescribed_nodes.size(); ++k) c.bc.prescribed_displacements.insert(c.bc.prescribed_displacements.end(), pull.begin(), pull.end());
  return c;
}

FemStaticOptions quasi_newton_options(double tolerance_mm) {
  FemStaticOptions o;
  o.nonlinear = FemNonlinearSolve::quasi_newton;
  o.tolerance_mm = tolerance_mm;
  o.linear_solve = FemLinearSolve::direct;
  return o;
}

// Newton to the relative `tolerance` on residual and displacement: the converged solution to compare with.
FemStaticOptions exact_newton(double tolerance, int load_steps) {
  FemStaticOptions o;
  o.residual_tolerance = tolerance;
  o.displacement_tolerance = tolerance;
  o.load_steps = load_steps;
  return o;
}

TEST(FemQuasiNewton, ReachesNewtonsSolutionWithinItsBudgetOnEveryLaw) {
  // A bend and a stretch of a third of the column's height: rotations the linear law gets wrong, so the
  // laws' solutions differ by millimetres, and each must match its own Newton solution.
  for (const FemLaw law : {FemLaw::linear, FemLaw::corotational, FemLaw::stvk, FemLaw::neo_hookean, FemLaw::mooney_rivlin}) {
    SCOPED_TRACE(fem_law_name(law));
    const GrabbedColumn c = grabbed_column(law, {8, 0, 4});
    const FemStaticResult newton = solve_fem_static(c.model, c.bc, {}, exact_newton(1e-10, 4));
    ASSERT_TRUE(newton.report.converged);
    const double budget = 1e-3;
    FemStaticOptions qn = quasi_newton_options(budget);
    qn.load_steps = 4;
    const FemStaticResult quasi = solve_fem_static(c.model, c.bc, {}, qn);
    ASSERT_TRUE(quasi.report.converged);
    EXPECT_EQ(quasi.report.quasi_newton_fallbacks, 0);
    EXPECT_GT(quasi.report.quasi_newton_iterations, 0);
    EXPECT_EQ(quasi.report.newton_iterations, 0);
    EXPECT_EQ(quasi.report.factorizations, 1);  // the rest stiffness, once for all load steps
    // L-BFGS's last step estimates its remaining error: within a few budgets of the exact solution.
    EXPECT_LT(max_abs_difference(quasi.displacements, newton.displacements), 5 * budget);
    // The reactions at the held nodes too (uN): the same equilibrium.
    EXPECT_LT(max_abs_difference(quasi.reactions, newton.reactions), 1e-2 * test::max_abs(newton.reactions));
  }
}

// The error estimate (FemStaticReport::error_estimate_mm, what the live page shows): the next L-BFGS
// step's largest nodal displacement, against the converged solution's true largest nodal distance, on a
// bent and stretched column solved to loose budgets. Newton's report has none.
TEST(FemQuasiNewton, EstimatesItsRemainingErrorWithinAFactorOfTheTrueOne) {
  const GrabbedColumn c = grabbed_column(FemLaw::neo_hookean, {8, 0, 4});
  const FemStaticResult newton = solve_fem_static(c.model, c.bc, {}, exact_newton(1e-11, 4));
  ASSERT_TRUE(newton.report.converged);
  EXPECT_TRUE(std::isnan(newton.report.error_estimate_mm));
  const auto largest_nodal = [](const std::vector<double>& a, const std::vector<double>& b) {
    double most = 0;
    for (size_t i = 0; i < a.size(); i += 3)
      most = std::max(most, std::hypot(a[i] - b[i], a[i + 1] - b[i + 1], a[i + 2] - b[i + 2]));
    return most;
  };
  for (const double budget : {0.1, 0.03, 0.01}) {
    SCOPED_TRACE(budget);
    FemStaticOptions qn = quasi_newton_options(budget);
    qn.load_steps = 4;
    const FemStaticResult quasi = solve_fem_static(c.model, c.bc, {}, qn);
    ASSERT_TRUE(quasi.report.converged);
    const double truth = largest_nodal(quasi.displacements, newton.displacements);
    const double estimate = quasi.report.error_estimate_mm;
    std::printf("budget %.3g mm: true error %.3g mm, estimate %.3g mm\n", budget, truth, estimate);
    ASSERT_TRUE(std::isfinite(estimate));
    EXPECT_GT(estimate, 0.0);
    EXPECT_LT(estimate, 3 * truth + 1e-6);
    EXPECT_GT(estimate, truth / 3 - 1e-6);
  }
}

TEST(FemQuasiNewton, GravityAloneConvergesToNewtonsSolution) {
  // No held component moves: no lift, only L-BFGS iterations from rest (a column sagging sideways by a
  // tenth of its height; a ten times softer one, sagging by half, needs more than the 60 iterations and
  // goes on with Newton: the rest stiffness is a poor model of large rotations, Liu et al. section 6).
  FemModel m = fem_box_model(FemLaw::neo_hookean, {2, 2, 8}, {8, 8, 32}, 1e4, 0.45);
  FemBoundaryConditions bc;
  bc.fixed_nodes = nodes_where(m, 2, 0);
  FemLoads loads;
  loads.gravity = {9810, 0, 0};
  const FemStaticResult newton = solve_fem_static(m, bc, loads, exact_newton(1e-10, FemStaticOptions{}.load_steps));
  const FemStaticResult quasi = solve_fem_static(m, bc, loads, quasi_newton_options(1e-4));
  ASSERT_TRUE(quasi.report.converged);
  EXPECT_GT(test::max_abs(newton.displacements), 1.0);  // a real sag, not a rounding
  EXPECT_EQ(quasi.report.quasi_newton_fallbacks, 0);
  std::printf("gravity on a column: a %.3g mm sag, Newton %d iterations, quasi-Newton %d\n", test::max_abs(newton.displacements),
              newton.report.newton_iterations, quasi.report.quasi_newton_iterations);
  EXPECT_LT(max_abs_difference(quasi.displacements, newton.displacements), 1e-3);
}

TEST(FemQuasiNewton, AQuasiStaticSequenceKeepsTheRestFactorAcrossFramesAndRefactorisesANewHeldSet) {
  const GrabbedColumn c = grabbed_column(FemLaw::neo_hookean, {0, 0, 0});
  FemStaticSolver solver(c.model, quasi_newton_options(1e-3));
  FemStaticSolver newton_solver(c.model, [] {
    FemStaticOptions o;
    o.tolerance_mm = 1e-3;
    o.linear_solve = FemLinearSolve::direct;
    return o;
  }());
  std::vector<double> u, un;
  int factorizations = 0, newton_factorizations = 0;
  FemBoundaryConditions bc = c.bc;
  for (int frame = 1; frame <= 20; ++frame) {  // a drag of 10 mm in 20 frames
    for (size_t k = 0; k < bc.prescribed_nodes.size(); ++k) bc.prescribed_displacements[3 * k] = 0.5 * frame;
    const FemStaticResult r = solver.solve(bc, {}, frame > 1 ? &u : nullptr);
    const FemStaticResult rn = newton_solver.solve(bc, {}, frame > 1 ? &un : nullptr);
    ASSERT_TRUE(r.report.converged);
    u = r.displacements;
    un = rn.displacements;
    factorizations += r.report.factorizations;
    newton_factorizations += rn.report.factorizations;
    EXPECT_EQ(r.report.quasi_newton_fallbacks, 0) << "frame " << frame;
    EXPECT_LT(max_abs_difference(u, un), 5e-3) << "frame " << frame;
  }
  EXPECT_EQ(factorizations, 1);
  std::printf("a 20-frame drag: %d factorisations (Newton's: %d)\n", factorizations, newton_factorizations);
  // Another held set (the grab lets go of half its nodes): the rest stiffness is factorised again.
  bc.prescribed_nodes.resize(bc.prescribed_nodes.size() / 2);
  bc.prescribed_displacements.resize(3 * bc.prescribed_nodes.size());
  const FemStaticResult r = solver.solve(bc, {}, &u);
  EXPECT_TRUE(r.report.converged);
  EXPECT_EQ(r.report.factorizations, 1);
}

TEST(FemQuasiNewton, TooFewIterationsGoOnWithNewton) {
  const GrabbedColumn c = grabbed_column(FemLaw::neo_hookean, {8, 0, 4});
  FemStaticOptions o = quasi_newton_options(1e-4);
  o.max_quasi_newton_iterations = 2;
  const FemStaticResult r = solve_fem_static(c.model, c.bc, {}, o);
  ASSERT_TRUE(r.report.converged);
  EXPECT_GT(r.report.quasi_newton_fallbacks, 0);
  EXPECT_GT(r.report.newton_iterations, 0);
  FemStaticOptions exact;
  exact.tolerance_mm = 1e-6;
  EXPECT_LT(max_abs_difference(r.displacements, solve_fem_static(c.model, c.bc, {}, exact).displacements), 1e-3);
}

TEST(FemQuasiNewton, ImplicitStepsMatchNewtonsWithinTheBudget) {
  // The same quasi-Newton iteration solves each implicit step (the rest tangent plus the step's mass term).
  FemModel m = fem_box_model(FemLaw::neo_hookean, {2, 2, 6}, {8, 8, 24}, 3e4, 0.45);
  FemImplicitOptions on, oq;
  on.newton.tolerance_mm = 1e-6;
  oq.newton = quasi_newton_options(1e-6);
  FemImplicitDynamics newton(m, on), quasi(m, oq);
  const auto base = nodes_where(m, 2, 0);
  const auto top = nodes_where(m, 2, 24);
  for (auto* d : {&newton, &quasi}) {
    d->set_supports(base);
    d->set_prescribed(top, std::vector<double>(3 * top.size(), 0.0));
  }
  std::vector<double> target(3 * top.size(), 0.0);
  for (int step = 1; step <= 30; ++step) {
    for (size_t k = 0; k < top.size(); ++k) target[3 * k] = step <= 15 ? 0.4 * step : 6.0;  // pulled 6 mm, then held
    newton.set_prescribed(top, target);
    quasi.set_prescribed(top, target);
    newton.step();
    quasi.step();
  }
  EXPECT_LT(max_abs_difference(newton.displacements(), quasi.displacements()), 1e-4);
}

TEST(FemQuasiNewton, OptionsOutOfRangeNameTheirField) {
  const GrabbedColumn c = grabbed_column(FemLaw::neo_hookean, {1, 0, 0});
  FemStaticOptions o = quasi_newton_options(1e-3);
  o.lbfgs_history = 0;
  try {
    solve_fem_static(c.model, c.bc, {}, o);
    FAIL() << "lbfgs_history 0 was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("lbfgs_history"), std::string::npos) << e.what();
  }
  o = quasi_newton_options(1e-3);
  o.max_quasi_newton_iterations = 0;
  EXPECT_THROW(solve_fem_static(c.model, c.bc, {}, o), InputError);
}

}  // namespace
}  // namespace ctsurg::sim
