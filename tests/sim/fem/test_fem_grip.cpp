// Tests of the volume grip (fem_grip.h): its integral is the weighted volume of the sphere on any mesh and
// moves continuously with the sphere; the reaction force and the field converge as the mesh is refined;
// the grip's force balances the supports' reactions; quasi-Newton reaches Newton's solution with a grip;
// implicit midpoint steps follow a moving grip; bad arguments are refused by name; a force spread over the
// material by the grip's weights (fem_tools.h) is its force and converges as the mesh is refined.
#include "ctsurg/sim/fem/fem_grip.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/fem/fem_implicit_dynamics.h"
#include "ctsurg/sim/fem/fem_static_solver.h"
#include "ctsurg/sim/fem/fem_tools.h"
#include "fem_test_models.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace ctsurg::sim {
namespace {

using test::fem_box_model;
using test::nodes_where;

// The grip's volume in closed form: 4 pi integral of w(d) d^2 dd, w the smoothstep over [r - e/2, r + e/2].
double weighted_sphere_volume(double r, double e) {
  const double inner = r - e / 2;
  double v = 4.0 / 3.0 * std::numbers::pi * inner * inner * inner;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {  // midpoint rule over the band (smooth integrand: 1e-9 relative)
    const double t = (i + 0.5) / n, d = inner + t * e;
    v += 4 * std::numbers::pi * (1 - t * t * (3 - 2 * t)) * d * d * e / n;
  }
  return v;
}

double sum(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return s;
}

TEST(FemGrip, IntegratesTheWeightedSphereOnEveryMeshAndOrder) {
  const double r = 3, e = 0.75, exact = weighted_sphere_volume(r, e);
  for (const int order : {1, 2})
    for (const int cells : {3, 5, 9}) {
      SCOPED_TRACE("order " + std::to_string(order) + ", cells " + std::to_string(cells));
      const auto box = fem_box_mesh({cells, cells, cells}, {10, 10, 10});
      const FemModel m = order == 1 ? build_fem_model(box.nodes, box.tets, test::fem_material(FemLaw::linear))
                                    : build_quadratic_fem_model(box.nodes, box.tets, test::fem_material(FemLaw::linear));
      const std::vector<double> u(3 * static_cast<size_t>(m.node_count()), 0.0);
      const FemGrip g = fem_capture_grip(m, u, {5.1, 4.9, 5.2}, r, e, 2.0);
      EXPECT_NEAR(g.volume_mm3, exact, 2e-3 * exact);
      // sum_ab P_ab = k integral of w (the shape functions sum to 1), and P is symmetric.
      EXPECT_NEAR(sum(g.matrices), 2.0 * g.volume_mm3, 1e-9 * g.volume_mm3);
      const int npe = m.nodes_per_element();
      for (size_t k = 0; k < g.elements.size(); ++k)
        for (int a = 0; a < npe; ++a)
          for (int b = 0; b < npe; ++b) {
            const double* p = &g.matrices[static_cast<size_t>(npe * npe) * k];
            ASSERT_NEAR(p[npe * a + b], p[npe * b + a], 1e-12);
          }
    }
}

TEST(FemGrip, MovesContinuouslyWithItsSphereWhereANodeSetJumps) {
  const auto box = fem_box_mesh({4, 4, 4}, {10, 10, 10});
  const FemModel m = build_fem_model(box.nodes, box.tets, test::fem_material(FemLaw::linear));
  const std::vector<double> u(3 * static_cast<size_t>(m.node_count()), 0.0);
  // Node (5, 5, 5) lies 2.5 mm from the centre (5, 5, 7.5): a sphere of 2.49 misses it, 2.51 holds it.
  std::vector<uint8_t> free_axes(static_cast<size_t>(m.node_count()), 0);
  const auto small = free_nodes_in_sphere(m, u, free_axes, {5, 5, 7.5}, 2.49);
  const auto large = free_nodes_in_sphere(m, u, free_axes, {5, 5, 7.5}, 2.51);
  EXPECT_LT(small.size(), large.size());
  const FemGrip a = fem_capture_grip(m, u, {5, 5, 7.5}, 2.49, 0.6, 1.0), b = fem_capture_grip(m, u, {5, 5, 7.5}, 2.51, 0.6, 1.0);
  const double relative = std::abs(b.volume_mm3 - a.volume_mm3) / a.volume_mm3;
  EXPECT_LT(relative, 0.03);  // the volume's own change, 3 x 0.02 / 2.5
  EXPECT_GT(relative, 0.01);
}

// A 10 x 10 x 30 mm column (linear law), its base held, gripped over a sphere of 4 mm at (5, 5, 22) and
// moved 3 mm along x: the grip's reaction and the top's displacement at `cells` across.
struct GripResult {
  std::array<double, 6> load{};
  std::array<double, 3> top{};  // the deflection at z = 10 mm
  double supports[3] = {0, 0, 0};
};

GripResult grip_column(int cells, FemLaw law, FemNonlinearSolve nonlinear = FemNonlinearSolve::newton, double tolerance_mm = 0,
                       int order = 1, double edge = 1) {
  const auto box = fem_box_mesh({cells, cells, 3 * cells}, {10, 10, 30});
  const FemModel m = order == 1 ? build_fem_model(box.nodes, box.tets, test::fem_material(law))
                                : build_quadratic_fem_model(box.nodes, box.tets, test::fem_material(law));
  FemBoundaryConditions bc;
  bc.fixed_nodes = nodes_where(m, 2, 0);
  std::vector<double> u(3 * static_cast<size_t>(m.node_count()), 0.0);
  FemLoads loads;
  loads.grips.push_back(fem_capture_grip(m, u, {5, 5, 22}, 4, edge, 1000 * 3e4 / 16));
  fem_grip_move(loads.grips[0], {3, 0, 0});
  FemStaticOptions o;
  o.residual_tolerance = 1e-10;
  o.displacement_tolerance = 1e-10;
  o.nonlinear = nonlinear;
  o.tolerance_mm = tolerance_mm;
  o.linear_solve = FemLinearSolve::direct;
  const FemStaticResult r = solve_fem_static(m, bc, loads, o);
  EXPECT_TRUE(r.report.converged);
  GripResult out;
  out.load = fem_grip_load(m, loads.grips[0], r.displacements, {8, 5, 22});
  // The column's deflection at a third of its height: the mean displacement of the nodes on z = 10 (a
  // bending column's section moves nearly as one).
  const std::vector<int32_t> section = nodes_where(m, 2, 10);
  for (int32_t n : section)
    for (int c = 0; c < 3; ++c) out.top[c] += r.displacements[3 * static_cast<size_t>(n) + c] / static_cast<double>(section.size());
  for (int32_t n : bc.fixed_nodes)
    for (int c = 0; c < 3; ++c) out.supports[c] += r.reactions[3 * static_cast<size_t>(n) + c] * 1e-6;
  return out;
}

TEST(FemGrip, ReactionAndFieldConvergeUnderRefinement) {
  for (const int order : {1, 2}) {
  SCOPED_TRACE("order " + std::to_string(order));
  const int c0 = 2;
  const GripResult coarse = grip_column(c0, FemLaw::linear, FemNonlinearSolve::newton, 0, order, 4),
                   medium = grip_column(2 * c0, FemLaw::linear, FemNonlinearSolve::newton, 0, order, 4),
                   fine = grip_column(4 * c0, FemLaw::linear, FemNonlinearSolve::newton, 0, order, 4);
  // The reaction pulls along +x and the top follows the grip.
  EXPECT_GT(fine.load[0], 0);
  EXPECT_GT(fine.top[0], 0.3);
  const double f1 = std::abs(medium.load[0] - coarse.load[0]), f2 = std::abs(fine.load[0] - medium.load[0]);
  const double t1 = std::abs(medium.top[0] - coarse.top[0]), t2 = std::abs(fine.top[0] - medium.top[0]);
  std::printf("order %d: grip reaction Fx (N) at %d, %d, %d cells: %.6f %.6f %.6f; deflection at z = 10 (mm): %.5f %.5f %.5f\n", order, c0, 2 * c0, 4 * c0,
              coarse.load[0], medium.load[0], fine.load[0], coarse.top[0], medium.top[0], fine.top[0]);
  // Each halving of h shrinks the change: a converging sequence (linear tets: about first order in the
  // force, second in the field).
  EXPECT_LT(f2, 0.7 * f1);
  EXPECT_LT(t2, 0.7 * t1);
  if (order == 2) {  // P2 is in its asymptotic range here: the last level changes the answer by a few per mille
    EXPECT_LT(f2 / fine.load[0], 0.025);
    EXPECT_LT(t2 / fine.top[0], 0.01);
  }
  }
}

TEST(FemGrip, ItsForceBalancesTheSupportsReactions) {
  for (const FemLaw law : {FemLaw::linear, FemLaw::neo_hookean}) {
    SCOPED_TRACE(fem_law_name(law));
    const GripResult r = grip_column(3, law);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(r.load[c] + r.supports[c], 0.0, 1e-6 * std::abs(r.load[0]));
  }
}

// The column (base held) under a force tool of 0.05 N along x over a 4 mm sphere at (5, 5, 22): spread
// over the material by volume (grip: volume, fem_tools.h) or shared by the free nodes in the sphere.
struct ForceResult {
  double total[3] = {0, 0, 0};  // the nodal forces' sum, N
  std::array<double, 6> load{};  // the tool's load (tool_load) at the solution
  std::array<double, 6> rest_load{};  // and at rest
  double deflection = 0;         // x at z = 10 mm, as grip_column's
};

ForceResult force_column(int cells, int order, HoldGrip grip) {
  const auto box = fem_box_mesh({cells, cells, 3 * cells}, {10, 10, 30});
  const FemModel m = order == 1 ? build_fem_model(box.nodes, box.tets, test::fem_material(FemLaw::linear))
                                : build_quadratic_fem_model(box.nodes, box.tets, test::fem_material(FemLaw::linear));
  FemBoundaryConditions bc;
  bc.fixed_nodes = nodes_where(m, 2, 0);
  std::vector<uint8_t> held(static_cast<size_t>(m.node_count()), 0);
  for (const int32_t n : bc.fixed_nodes) held[static_cast<size_t>(n)] = kAllAxes;
  FemToolHolds holds(m, held, "column.yaml");
  ToolInput f;
  f.acts = ToolPrimitive::load;
  f.label = "tools[0] (force)";
  f.radius_mm = 4;
  f.centre = f.start_centre = {5, 5, 22};
  f.active = true;
  f.force_n = {0.05, 0, 0};
  f.grip = grip;
  f.grip_edge_mm = 4;
  const std::vector<double> rest(3 * static_cast<size_t>(m.node_count()), 0.0);
  EXPECT_TRUE(holds.update_forces({f}, rest, false));
  FemLoads loads;
  loads.forces = holds.nodal_forces();
  FemStaticOptions o;
  o.linear_solve = FemLinearSolve::direct;
  const FemStaticResult r = solve_fem_static(m, bc, loads, o);
  EXPECT_TRUE(r.report.converged);
  ForceResult out;
  for (size_t i = 0; i < loads.forces.size(); ++i) out.total[i % 3] += loads.forces[i] * 1e-6;
  EXPECT_TRUE(holds.load(0, r.displacements, nullptr, out.load));
  EXPECT_TRUE(holds.load(0, rest, nullptr, out.rest_load));
  const std::vector<int32_t> section = nodes_where(m, 2, 10);
  for (const int32_t n : section) out.deflection += r.displacements[3 * static_cast<size_t>(n)] / static_cast<double>(section.size());
  return out;
}

TEST(FemGrip, AVolumeForceIsItsForceAndConvergesUnderRefinement) {
  for (const int order : {1, 2}) {
    SCOPED_TRACE("order " + std::to_string(order));
    ForceResult r[3], by_nodes[3];
    for (int k = 0; k < 3; ++k) {
      r[k] = force_column(2 << k, order, HoldGrip::volume);
      by_nodes[k] = force_column(2 << k, order, HoldGrip::nodes);
      // Every node's share counted (on P2 the vertices' are negative, as a body force's consistent load is):
      // the sum is the force, and the tool's load says so.
      EXPECT_NEAR(r[k].total[0], 0.05, 1e-12);
      EXPECT_NEAR(r[k].total[1], 0.0, 1e-12);
      EXPECT_NEAR(r[k].load[0], 0.05, 1e-12);
      // Spread evenly over a region symmetric about the tool's centre (the sphere and its band, clipped
      // alike on either side of the column): at rest no moment about the centre but the quadrature's.
      EXPECT_LT(std::hypot(r[k].rest_load[3], r[k].rest_load[4], r[k].rest_load[5]), 0.05 * 0.01);  // N mm: the centroid within 0.01 mm
    }
    std::printf("order %d: deflection at z = 10 (mm) at 2, 4, 8 cells: by volume %.5f %.5f %.5f, by the nodes in the sphere %.5f %.5f %.5f\n",
                order, r[0].deflection, r[1].deflection, r[2].deflection, by_nodes[0].deflection, by_nodes[1].deflection,
                by_nodes[2].deflection);
    // Each halving of h shrinks the change: linear tets slowly (first order in bending), quadratic ones
    // about threefold a level and within 1 % at 8 cells. (The node-shared force on P2 changes by 0.008
    // then 0.011 mm here: which nodes lie in the sphere, not the elements, sets its last digits.)
    const double d1 = std::abs(r[1].deflection - r[0].deflection), d2 = std::abs(r[2].deflection - r[1].deflection);
    EXPECT_GT(r[2].deflection, 0.0);
    EXPECT_LT(d2, (order == 1 ? 0.7 : 0.5) * d1);
    if (order == 2) {
      EXPECT_LT(d2 / r[2].deflection, 0.01);
    }
  }
}

TEST(FemGrip, QuasiNewtonReachesNewtonsSolutionWithAGrip) {
  const GripResult newton = grip_column(3, FemLaw::neo_hookean);
  const GripResult qn = grip_column(3, FemLaw::neo_hookean, FemNonlinearSolve::quasi_newton, 1e-3);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(qn.top[c], newton.top[c], 2e-3);
  EXPECT_NEAR(qn.load[0], newton.load[0], 1e-3 * std::abs(newton.load[0]));
}

TEST(FemGrip, ImplicitMidpointStepsFollowAMovingGrip) {
  // The column's implicit dynamics under a grip that moves 2 mm over 0.1 s, then holds: the grip holds
  // the material near its target, nothing goes non-finite.
  const FemModel m = fem_box_model(FemLaw::neo_hookean, {2, 2, 6}, {10, 10, 30});
  FemImplicitOptions o;
  o.dt = 1.0 / 60;
  o.scheme = FemImplicitScheme::midpoint;
  FemImplicitDynamics d(m, o);
  d.set_supports(nodes_where(m, 2, 0), {});
  const std::vector<double> rest(3 * static_cast<size_t>(m.node_count()), 0.0);
  FemGrip g = fem_capture_grip(m, rest, {5, 5, 22}, 4, 1, 1000 * 3e4 / 16);
  for (int s = 1; s <= 30; ++s) {
    fem_grip_move(g, {std::min(2.0, 2.0 * s / 6), 0, 0});
    d.set_grips({g});
    d.step(1);
  }
  const std::array<double, 6> load = fem_grip_load(m, g, d.displacements(), {7, 5, 22});
  for (double v : load) EXPECT_TRUE(std::isfinite(v));
  // Inside the sphere the material is within a tenth of the travel of its target.
  const std::vector<double>& u = d.displacements();
  for (size_t k = 0; k < g.nodes.size(); ++k) {
    const size_t n = static_cast<size_t>(g.nodes[k]);
    if (std::hypot(m.nodes[3 * n] - 5, m.nodes[3 * n + 1] - 5, m.nodes[3 * n + 2] - 22) < 2) {
      EXPECT_NEAR(u[3 * n], 2.0, 0.2);
    }
  }
}

TEST(FemGrip, RefusesBadArgumentsByName) {
  const FemModel m = fem_box_model(FemLaw::linear, {2, 2, 2}, {10, 10, 10});
  const std::vector<double> u(3 * static_cast<size_t>(m.node_count()), 0.0);
  const auto field_of = [&](auto call) {
    try {
      call();
    } catch (const InputError& e) {
      return e.field();
    }
    return std::string("(none)");
  };
  EXPECT_EQ(field_of([&] { fem_capture_grip(m, u, {5, 5, 5}, -1, 0.5, 1); }), "radius_mm");
  EXPECT_EQ(field_of([&] { fem_capture_grip(m, u, {5, 5, 5}, 2, 3, 1); }), "edge_mm");
  EXPECT_EQ(field_of([&] { fem_capture_grip(m, u, {5, 5, 5}, 2, 0.5, 0); }), "stiffness");
  EXPECT_EQ(field_of([&] { fem_capture_grip(m, {1.0}, {5, 5, 5}, 2, 0.5, 1); }), "displacements");
  // Outside the body: an empty grip.
  EXPECT_TRUE(fem_capture_grip(m, u, {50, 50, 50}, 2, 0.5, 1).elements.empty());
  // A grip whose arrays do not match is refused by the solver.
  FemLoads loads;
  loads.grips.push_back(fem_capture_grip(m, u, {5, 5, 5}, 2, 0.5, 1));
  loads.grips[0].target.pop_back();
  FemBoundaryConditions bc;
  bc.fixed_nodes = nodes_where(m, 2, 0);
  EXPECT_EQ(field_of([&] { solve_fem_static(m, bc, loads); }), "grips");
}

}  // namespace
}  // namespace ctsurg::sim
