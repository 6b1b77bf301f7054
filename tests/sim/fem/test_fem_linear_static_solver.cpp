// Tests of sim/fem_linear_static_solver.h: the factorised solve agrees with the Newton-CG solver
// (solve_fem_static) for grabs, forces and gravity; repeated solves reuse the factor and the columns
// and are exactly linear in the load; reactions balance the loads; both force paths (columns,
// back-substitution) agree; results do not depend on the thread count; bad input is refused.
#include "ctsurg/sim/fem/fem_linear_static_solver.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/fem/fem_box_mesh.h"
#include "fem_test_models.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <string>

namespace ctsurg::sim {
namespace {

using test::max_abs;
using test::max_abs_difference;

FemModel box_model(FemLaw law = FemLaw::linear) { return test::fem_box_model(law, {5, 5, 6}, {10, 10, 12}); }

using test::nodes_where;

// The centre of the top face (z = 12) within radius 2.5 mm.
std::vector<int32_t> top_centre(const FemModel& m) {
  std::vector<int32_t> out;
  for (int32_t i : nodes_where(m, 2, 12.0))
    if (std::hypot(m.nodes[3 * i] - 5, m.nodes[3 * i + 1] - 5) <= 2.5) out.push_back(i);
  return out;
}

struct Case {
  FemBoundaryConditions supports;
  std::vector<int32_t> grab;
  std::vector<double> grab_d;
  FemLoads loads;
};

// Bottom fixed; top centre pulled 0.3 mm sideways and 0.5 mm down; a 2e4 uN (20 mN) force on a side
// node; gravity along -z.
Case loaded_box(const FemModel& m) {
  Case c;
  c.supports.fixed_nodes = nodes_where(m, 2, 0.0);
  c.grab = top_centre(m);
  for (std::size_t g = 0; g < c.grab.size(); ++g) c.grab_d.insert(c.grab_d.end(), {0.3, 0.0, -0.5});
  c.loads.forces.assign(m.nodes.size(), 0.0);
  const auto side = nodes_where(m, 0, 10.0);
  c.loads.forces[3 * side[side.size() / 2] + 1] = 2e4;
  c.loads.gravity = {0, 0, -9810};
  return c;
}

TEST(FemLinearStaticSolver, AgreesWithTheNewtonConjugateGradientSolver) {
  const FemModel m = box_model();
  const Case c = loaded_box(m);
  FemLinearStaticSolver solver(m, c.supports);
  const FemStaticResult direct = solver.solve(c.grab, c.grab_d, c.loads);
  ASSERT_TRUE(direct.report.converged);
  EXPECT_LT(direct.report.relative_residual, 1e-10);

  FemBoundaryConditions bc = c.supports;
  bc.prescribed_nodes = c.grab;
  bc.prescribed_displacements = c.grab_d;
  FemStaticOptions o;
  o.cg_tolerance = 1e-13;
  const FemStaticResult cg = solve_fem_static(m, bc, c.loads, o);
  ASSERT_TRUE(cg.report.converged);
  const double scale = max_abs(cg.displacements);
  EXPECT_GT(scale, 0.4);
  EXPECT_LT(max_abs_difference(direct.displacements, cg.displacements), 1e-9 * scale);
  EXPECT_LT(max_abs_difference(direct.reactions, cg.reactions), 1e-7 * max_abs(cg.reactions));
  for (std::size_t g = 0; g < c.grab.size(); ++g)  // grabbed nodes sit exactly at their targets
    for (int a = 0; a < 3; ++a) EXPECT_EQ(direct.displacements[3 * c.grab[g] + a], c.grab_d[3 * g + a]);
}

TEST(FemLinearStaticSolver, ReactionsBalanceTheLoads) {
  const FemModel m = box_model();
  const Case c = loaded_box(m);
  FemLinearStaticSolver solver(m, c.supports);
  const FemStaticResult r = solver.solve(c.grab, c.grab_d, c.loads);
  for (int a = 0; a < 3; ++a) {  // sum of reactions = -(sum of external forces), per axis
    double reactions = 0, external = 0;
    for (int32_t i = 0; i < m.node_count(); ++i) {
      reactions += r.reactions[3 * i + a];
      external += c.loads.forces[3 * i + a] + m.node_mass[i] * c.loads.gravity[a];
    }
    EXPECT_NEAR(reactions, -external, 1e-8 * (std::abs(external) + max_abs(r.reactions))) << "axis " << a;
  }
}

TEST(FemLinearStaticSolver, RepeatedSolvesReuseTheColumnsAndAreLinearInTheLoad) {
  const FemModel m = box_model();
  Case c = loaded_box(m);
  c.loads.gravity = {0, 0, 0};
  FemLinearStaticSolver solver(m, c.supports);
  const FemStaticResult once = solver.solve(c.grab, c.grab_d, c.loads);
  const int64_t columns = solver.stats().columns;
  EXPECT_EQ(columns, 3 * static_cast<int64_t>(c.grab.size() + 1));  // grabbed nodes and the loaded node
  Case twice = c;
  for (double& d : twice.grab_d) d *= 2;
  for (double& f : twice.loads.forces) f *= 2;
  const FemStaticResult r2 = solver.solve(twice.grab, twice.grab_d, twice.loads);
  EXPECT_EQ(solver.stats().columns, columns);  // nothing new to compute
  for (std::size_t d = 0; d < once.displacements.size(); ++d)
    EXPECT_NEAR(r2.displacements[d], 2 * once.displacements[d], 1e-12 * max_abs(once.displacements));
  // A new grab set adds only its own nodes' columns.
  const FemStaticResult none = solver.solve({}, {}, c.loads);
  EXPECT_EQ(solver.stats().columns, columns);
  EXPECT_TRUE(none.report.converged);
}

TEST(FemLinearStaticSolver, ColumnAndBackSubstitutionPathsAgree) {
  const FemModel m = box_model();
  Case c = loaded_box(m);
  for (int32_t i : nodes_where(m, 0, 0.0)) c.loads.forces[3 * i] += 500;  // many loaded nodes
  FemLinearStaticSolver columns(m, c.supports);
  FemLinearSolverOptions o;
  o.max_force_nodes = 0;  // always one back-substitution for the forces
  FemLinearStaticSolver back(m, c.supports, o);
  FemLinearSolverOptions many;
  many.max_force_nodes = 1000;
  FemLinearStaticSolver all_columns(m, c.supports, many);
  const auto a = back.solve(c.grab, c.grab_d, c.loads);
  const auto b = all_columns.solve(c.grab, c.grab_d, c.loads);
  EXPECT_LT(max_abs_difference(a.displacements, b.displacements), 1e-10 * max_abs(a.displacements));
  EXPECT_GT(all_columns.stats().columns, back.stats().columns);
}

// A grab of more than max_grab_nodes nodes factorises K_ff instead of computing 3|G| columns (a vessel's
// wall band took 134 s of columns at 16,000 nodes): the same displacements and reactions.
TEST(FemLinearStaticSolver, LargeGrabsFactoriseTheFreeBlockAndAgreeWithTheColumns) {
  const FemModel m = box_model();
  const Case c = loaded_box(m);
  ASSERT_GT(c.grab.size(), 1u);
  FemLinearStaticSolver columns(m, c.supports);
  FemLinearSolverOptions o;
  o.max_grab_nodes = 0;
  FemLinearStaticSolver direct(m, c.supports, o);
  const auto a = columns.solve(c.grab, c.grab_d, c.loads);
  const auto b = direct.solve(c.grab, c.grab_d, c.loads);
  ASSERT_TRUE(b.report.converged);
  EXPECT_LT(max_abs_difference(a.displacements, b.displacements), 1e-9 * max_abs(a.displacements));
  EXPECT_LT(max_abs_difference(a.reactions, b.reactions), 1e-9 * max_abs(a.reactions));
  EXPECT_EQ(direct.stats().columns, 0);  // none: the loads go into the K_ff solve too
  // The factor is kept for the same node set and remade for another.
  Case moved = c;
  for (double& d : moved.grab_d) d *= -1;
  const auto a2 = columns.solve(moved.grab, moved.grab_d, moved.loads);
  const auto b2 = direct.solve(moved.grab, moved.grab_d, moved.loads);
  EXPECT_LT(max_abs_difference(a2.displacements, b2.displacements), 1e-9 * max_abs(a2.displacements));
  const std::vector<int32_t> fewer(c.grab.begin(), c.grab.end() - 1);
  const std::vector<double> fewer_d(c.grab_d.begin(), c.grab_d.end() - 3);
  const auto a3 = columns.solve(fewer, fewer_d, c.loads);
  const auto b3 = direct.solve(fewer, fewer_d, c.loads);
  EXPECT_LT(max_abs_difference(a3.displacements, b3.displacements), 1e-9 * max_abs(a3.displacements));
}

TEST(FemLinearStaticSolver, ResultsDoNotDependOnTheThreadCount) {
  const FemModel m = box_model();
  const Case c = loaded_box(m);
  FemLinearSolverOptions one, two;
  one.threads = 1;
  two.threads = 2;
  FemLinearStaticSolver s1(m, c.supports, one), s2(m, c.supports, two);
  EXPECT_EQ(s1.solve(c.grab, c.grab_d, c.loads).displacements, s2.solve(c.grab, c.grab_d, c.loads).displacements);
}

std::string field_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.field();
  }
  return "(no InputError)";
}

TEST(FemLinearStaticSolver, BadInputIsRefusedWithTheField) {
  const FemModel m = box_model();
  const Case c = loaded_box(m);
  const FemModel nh = box_model(FemLaw::neo_hookean);
  EXPECT_EQ(field_of([&] { FemLinearStaticSolver s(nh, c.supports); }), "material");
  EXPECT_EQ(field_of([&] { FemLinearStaticSolver s(m, FemBoundaryConditions{}); }), "boundary conditions");
  FemBoundaryConditions with_grab = c.supports;
  with_grab.prescribed_nodes = c.grab;
  with_grab.prescribed_displacements = c.grab_d;
  EXPECT_EQ(field_of([&] { FemLinearStaticSolver s(m, with_grab); }), "prescribed_nodes");
  FemBoundaryConditions out_of_range;
  out_of_range.fixed_nodes = {m.node_count()};
  EXPECT_EQ(field_of([&] { FemLinearStaticSolver s(m, out_of_range); }), "fixed_nodes");

  FemLinearStaticSolver solver(m, c.supports);
  const int32_t fixed = c.supports.fixed_nodes.front();
  EXPECT_EQ(field_of([&] { solver.solve({fixed}, {0, 0, 1}, {}); }), "prescribed_nodes");
  EXPECT_EQ(field_of([&] { solver.solve({c.grab[0], c.grab[0]}, {0, 0, 1, 0, 0, 1}, {}); }), "prescribed_nodes");
  EXPECT_EQ(field_of([&] { solver.solve({c.grab[0]}, {0, 0}, {}); }), "prescribed_displacements");
  EXPECT_EQ(field_of([&] { solver.solve({c.grab[0]}, {0, 0, NAN}, {}); }), "prescribed_displacements");
  FemLoads short_forces;
  short_forces.forces = {1, 2, 3};
  EXPECT_EQ(field_of([&] { solver.solve({}, {}, short_forces); }), "forces");
  FemLoads bad_gravity;
  bad_gravity.gravity = {0, INFINITY, 0};
  EXPECT_EQ(field_of([&] { solver.solve({}, {}, bad_gravity); }), "gravity");
  // A refused call leaves the solver usable.
  EXPECT_TRUE(solver.solve(c.grab, c.grab_d, c.loads).report.converged);
}

}  // namespace
}  // namespace ctsurg::sim
