// Tests for ctsurg/sim/fem/fem_local_region.h (and its use by fem_engine.h and scenarios) on a
// 16 x 16 x 8 mm Neo-Hookean block of Kuhn tets fixed at its base, grabbed at the top centre: as the
// region's radius grows the composed field converges to the full nonlinear solve (equal to it, to the
// solver's tolerance, when the region covers the mesh); under a tiny load it is the linear solution;
// the region follows the tools (a moving grab, then another grab elsewhere); bad input names its field.
#include "ctsurg/sim/fem/fem_local_region.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/fem/fem_engine.h"
#include "ctsurg/sim/fem/fem_static_solver.h"
#include "ctsurg/sim/scenario/scenario.h"
#include "fem_test_models.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace ctsurg::sim {
namespace {

const std::array<int, 3> kRegionCells{8, 8, 4};
const std::array<double, 3> kRegionSize{16, 16, 8};

FemModel region_block(FemLaw law = FemLaw::neo_hookean) { return test::fem_box_model(law, kRegionCells, kRegionSize); }

FemBoundaryConditions base_fixed(const FemModel& m) {
  FemBoundaryConditions bc;
  bc.fixed_nodes = test::nodes_where(m, 2, 0.0);
  return bc;
}

// The top nodes within 2.1 mm of (x, y, 8).
std::vector<int32_t> top_nodes_near(const FemModel& m, double x, double y) {
  std::vector<int32_t> out;
  for (const int32_t i : test::nodes_where(m, 2, 8.0)) {
    const double dx = m.nodes[3 * static_cast<size_t>(i)] - x, dy = m.nodes[3 * static_cast<size_t>(i) + 1] - y;
    if (dx * dx + dy * dy < 2.1 * 2.1) out.push_back(i);
  }
  return out;
}

std::vector<double> lifted(size_t count, const std::array<double, 3>& d) {
  std::vector<double> out;
  for (size_t k = 0; k < count; ++k) out.insert(out.end(), d.begin(), d.end());
  return out;
}

FemStaticResult full_solve(const FemModel& m, const std::vector<int32_t>& grab, const std::vector<double>& d) {
  FemBoundaryConditions bc = base_fixed(m);
  bc.prescribed_nodes = grab;
  bc.prescribed_displacements = d;
  FemLoads loads;
  loads.gravity = {0, 0, -9810};
  return solve_fem_static(m, bc, loads);
}

TEST(FemLocalRegion, GeodesicDistancesFollowTheEdges) {
  const FemModel m = region_block();
  const int32_t corner = 0;  // (0, 0, 0)
  const std::vector<double> d = fem_geodesic_distances(m, {corner}, 5.0);
  EXPECT_EQ(d[0], 0.0);
  EXPECT_NEAR(d[1], 2.0, 1e-12);  // (2, 0, 0): one edge
  // (2, 2, 2): the Kuhn cell's main diagonal is an edge, 2 sqrt(3)
  const int32_t diag = 1 + 9 * (1 + 9 * 1);
  EXPECT_NEAR(d[static_cast<size_t>(diag)], 2 * std::sqrt(3.0), 1e-12);
  EXPECT_TRUE(std::isinf(d[8]));  // (16, 0, 0): beyond the limit
  for (size_t i = 0; i < d.size(); ++i) {
    if (std::isinf(d[i])) continue;
    const double euclid = std::sqrt(m.nodes[3 * i] * m.nodes[3 * i] + m.nodes[3 * i + 1] * m.nodes[3 * i + 1] + m.nodes[3 * i + 2] * m.nodes[3 * i + 2]);
    EXPECT_GE(d[i], euclid - 1e-12);  // a path through the mesh is never shorter than the straight line
  }
  try {
    fem_geodesic_distances(m, {m.node_count()}, 1.0);
    ADD_FAILURE() << "a seed out of range was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "seeds");
  }
}

// (a) Convergence to the full nonlinear solve as R grows; the whole mesh gives it to the tolerance.
TEST(FemLocalRegion, ConvergesToTheFullNonlinearSolveAsTheRegionGrows) {
  const FemModel m = region_block();
  const std::vector<int32_t> grab = top_nodes_near(m, 8, 8);
  ASSERT_EQ(grab.size(), 5u);
  const std::vector<double> d = lifted(grab.size(), {0, 0, 2.4});  // 30 % of the height
  const FemStaticResult full = full_solve(m, grab, d);
  ASSERT_TRUE(full.report.converged);
  FemLoads loads;
  loads.gravity = {0, 0, -9810};
  double previous = HUGE_VAL;
  double previous_residual = HUGE_VAL;
  int32_t previous_nodes = 0;
  double linear_error = 0;
  for (const double r : {5.0, 8.0, 12.0}) {
    FemLocalRegionOptions o;
    o.radius_mm = r;
    FemLocalRegionSolver local(m, base_fixed(m), o);
    const FemStaticResult res = local.solve(grab, d, loads, grab);
    ASSERT_TRUE(res.report.converged) << r;
    const FemLocalRegionReport& rep = local.report();
    const double error = test::max_abs_difference(res.displacements, full.displacements);
    EXPECT_LT(error, previous) << "R = " << r;
    EXPECT_LT(rep.interface_residual, previous_residual) << "R = " << r;
    EXPECT_GT(rep.region_nodes, previous_nodes);
    EXPECT_GT(rep.interface_nodes, 0);
    EXPECT_GT(rep.tool_load, 0);
    for (size_t g = 0; g < grab.size(); ++g)  // the grab holds its nodes exactly
      EXPECT_NEAR(res.displacements[3 * static_cast<size_t>(grab[g]) + 2], 2.4, 1e-12);
    if (r == 5.0) {
      // Against the linear solve of the whole mesh: no worse with the smallest region.
      const FemModel linear_model = region_block(FemLaw::linear);  // the solver keeps a reference to it
      FemLinearStaticSolver lin(linear_model, base_fixed(m));
      linear_error = test::max_abs_difference(lin.solve(grab, d, loads).displacements, full.displacements);
      EXPECT_LE(error, linear_error + 1e-6);
    }
    previous = error;
    previous_residual = rep.interface_residual;
    previous_nodes = rep.region_nodes;
  }
  EXPECT_LT(previous, 0.7 * linear_error) << previous << " vs " << linear_error;  // R = 12 mm against the linear model
  // Balance iterations: the interface's forces balanced (the region's law inside, linear outside).
  {
    FemLocalRegionOptions o;
    o.radius_mm = 8;
    FemLocalRegionSolver dirichlet(m, base_fixed(m), o);
    const double e0 = test::max_abs_difference(dirichlet.solve(grab, d, loads, grab).displacements, full.displacements);
    o.balance_iterations = 30;
    FemLocalRegionSolver balanced(m, base_fixed(m), o);
    const FemStaticResult res = balanced.solve(grab, d, loads, grab);
    ASSERT_TRUE(res.report.converged);
    EXPECT_GT(balanced.report().balance_iterations, 0);
    EXPECT_LT(balanced.report().balance_iterations, 30);
    EXPECT_LE(balanced.report().balance_change_mm, 1e-3);
    EXPECT_LT(balanced.report().interface_residual, 0.1 * dirichlet.report().interface_residual);
    EXPECT_LT(test::max_abs_difference(res.displacements, full.displacements), e0);
  }
  // A region covering the mesh: no interface, the full nonlinear solve.
  FemLocalRegionOptions o;
  o.radius_mm = 100;
  FemLocalRegionSolver whole(m, base_fixed(m), o);
  const FemStaticResult res = whole.solve(grab, d, loads, grab);
  EXPECT_EQ(whole.report().region_nodes, m.node_count());
  EXPECT_EQ(whole.report().region_tets, m.tet_count());
  EXPECT_EQ(whole.report().interface_nodes, 0);
  EXPECT_EQ(whole.report().interface_residual, 0);
  EXPECT_LT(test::max_abs_difference(res.displacements, full.displacements), 1e-7);
}

// (b) Under a tiny load the composed field is the linear solution.
TEST(FemLocalRegion, ATinyLoadGivesTheLinearSolution) {
  const FemModel m = region_block();
  const std::vector<int32_t> grab = top_nodes_near(m, 8, 8);
  const std::vector<double> d = lifted(grab.size(), {1e-5, 0, 1e-4});
  const FemModel linear_model = region_block(FemLaw::linear);  // the solver keeps a reference to it
  FemLinearStaticSolver lin(linear_model, base_fixed(m));
  const FemStaticResult linear = lin.solve(grab, d, {});
  FemLocalRegionOptions o;
  o.radius_mm = 5;
  FemLocalRegionSolver local(m, base_fixed(m), o);
  const FemStaticResult res = local.solve(grab, d, {}, grab);
  ASSERT_TRUE(res.report.converged);
  const double scale = test::max_abs(linear.displacements);
  EXPECT_GT(scale, 9e-5);
  EXPECT_LT(test::max_abs_difference(res.displacements, linear.displacements), 1e-4 * scale);
  EXPECT_LT(local.report().interface_residual, 1e-4 * local.report().tool_load);
}

ToolInput region_grab_at(const std::string& label, const Vec3& start, const Vec3& now, double start_s, bool active = true) {
  ToolInput g;
  g.acts = ToolPrimitive::hold;
  g.label = label;
  g.radius_mm = 2.1;
  g.active = active;
  g.start_s = start_s;
  g.start_centre = start;
  g.centre = now;
  return g;
}

FemEngineOptions local_options(double r) {
  FemEngineOptions o;
  o.solver = FemSolver::static_equilibrium;
  o.where = "s.yaml";
  o.local_region_mm = r;
  return o;
}

// The region's centroid (current positions) and whether node i is in it.
std::array<double, 3> region_centroid(const FemEngine& e) {
  std::array<double, 3> c{0, 0, 0};
  int n = 0;
  const std::vector<uint8_t>& flags = *e.local_region();
  for (size_t i = 0; i < flags.size(); ++i) {
    if (flags[i] == kFemOutsideRegion) continue;
    for (size_t a = 0; a < 3; ++a) c[a] += e.model().nodes[3 * i + a] + e.displacements()[3 * i + a];
    ++n;
  }
  for (double& v : c) v /= n;
  return c;
}

// (c) The region follows the tools: it rises with a grab that lifts, and moves to another grab.
TEST(FemLocalRegion, TheRegionFollowsTheTools) {
  FemModel m = region_block();
  FemBoundaryConditions supports = base_fixed(m);
  FemEngine e(std::move(m), std::move(supports), EmbeddedSurface(), {0, 0, 0}, local_options(6));
  ASSERT_NE(e.local_region(), nullptr);
  const Vec3 a{4, 4, 8}, b{12, 12, 8};
  const std::vector<int32_t> near_a = top_nodes_near(e.model(), 4, 4), near_b = top_nodes_near(e.model(), 12, 12);
  double z = -HUGE_VAL;
  int32_t nodes = -1;
  for (int f = 0; f <= 3; ++f) {
    const Vec3 now{4, 4, 8 + 0.6 * f};
    e.equilibrium({region_grab_at("tools[0] (grab)", a, now, 0), region_grab_at("tools[1] (grab)", b, b, 1, false)}, 0.1 * f);
    const std::vector<uint8_t>& flags = *e.local_region();
    for (const int32_t i : near_a) EXPECT_NE(flags[static_cast<size_t>(i)], kFemOutsideRegion);
    for (const int32_t i : near_b) EXPECT_EQ(flags[static_cast<size_t>(i)], kFemOutsideRegion);
    const std::array<double, 3> c = region_centroid(e);
    EXPECT_NEAR(c[0], 4, 1.0);
    EXPECT_NEAR(c[1], 4, 1.0);
    if (f > 0) {
      EXPECT_GT(c[2], z + 0.2);  // rises with the grab
      EXPECT_EQ(e.metrics().extra[4], static_cast<double>(nodes));  // the same tissue: the region's node count stays
    }
    z = c[2];
    nodes = static_cast<int32_t>(e.metrics().extra[4]);
  }
  // The first grab released, a second one at b: the region is there now.
  e.equilibrium({region_grab_at("tools[0] (grab)", a, a, 0, false), region_grab_at("tools[1] (grab)", b, {12, 12, 9}, 1)}, 1.0);
  const std::vector<uint8_t>& flags = *e.local_region();
  for (const int32_t i : near_a) EXPECT_EQ(flags[static_cast<size_t>(i)], kFemOutsideRegion);
  for (const int32_t i : near_b) EXPECT_NE(flags[static_cast<size_t>(i)], kFemOutsideRegion);
  const std::array<double, 3> c = region_centroid(e);
  EXPECT_NEAR(c[0], 12, 1.0);
  EXPECT_NEAR(c[1], 12, 1.0);
  // Two grabs at once (a third tool at a): two regions in one node set.
  e.equilibrium({region_grab_at("tools[0] (grab)", a, a, 0, false), region_grab_at("tools[1] (grab)", b, {12, 12, 9}, 1),
                 region_grab_at("tools[2] (grab)", a, a, 1.5)},
                1.5);
  int both = 0;
  for (const int32_t i : near_a) both += e.local_region()->at(static_cast<size_t>(i)) != kFemOutsideRegion;
  for (const int32_t i : near_b) both += e.local_region()->at(static_cast<size_t>(i)) != kFemOutsideRegion;
  EXPECT_EQ(both, static_cast<int>(near_a.size() + near_b.size()));
  const std::vector<std::pair<std::string, std::string>> names = e.extra_metrics();
  ASSERT_EQ(names.size(), e.metrics().extra.size());
  EXPECT_EQ(names[4].first, "region_nodes");
  EXPECT_EQ(names[7].first, "interface_residual");
  EXPECT_GT(e.metrics().extra[7], 0);
}

// Each tool may have its own radius (ToolInput::local_region_mm, a scenario tool's local_region_mm): two
// grabs lifted together, one with a 3 mm region and one with the engine's 6 mm; then the radii swapped.
TEST(FemLocalRegion, EachToolCanHaveItsOwnRadius) {
  FemModel m = region_block();
  FemBoundaryConditions supports = base_fixed(m);
  FemEngine e(std::move(m), std::move(supports), EmbeddedSurface(), {0, 0, 0}, local_options(6));
  const Vec3 a{4, 4, 8}, b{12, 12, 8};
  // Region nodes within 7 mm (rest) of each grab's centre.
  const auto around = [&](const Vec3& c) {
    int count = 0;
    const std::vector<uint8_t>& flags = *e.local_region();
    for (int32_t i = 0; i < e.model().node_count(); ++i) {
      const double* x = &e.model().nodes[3 * static_cast<size_t>(i)];
      const double d2 = (x[0] - c[0]) * (x[0] - c[0]) + (x[1] - c[1]) * (x[1] - c[1]) + (x[2] - c[2]) * (x[2] - c[2]);
      count += d2 < 49 && flags[static_cast<size_t>(i)] != kFemOutsideRegion;
    }
    return count;
  };
  ToolInput ga = region_grab_at("tools[0] (grab)", a, {4, 4, 8.5}, 0), gb = region_grab_at("tools[1] (grab)", b, {12, 12, 8.5}, 0);
  ga.local_region_mm = 3;  // b: 0, the engine's 6 mm
  e.equilibrium({ga, gb}, 0.1);
  const int small_a = around(a), large_b = around(b);
  EXPECT_GT(small_a, 0);
  EXPECT_GT(large_b, small_a + 10) << "a's 3 mm region is smaller than b's 6 mm one";
  ga.local_region_mm = 6;
  gb.local_region_mm = 3;
  e.equilibrium({ga, gb}, 0.2);
  // Swapped: a's region is now the larger (the Kuhn split is not symmetric under the swap, so the counts
  // match the other grab's within a few nodes, not exactly).
  EXPECT_GT(around(a), around(b) + 10);
  EXPECT_NEAR(around(a), large_b, 5);
  EXPECT_NEAR(around(b), small_a, 5);
  // In a scenario: `local_region_mm` on a grab, clamp or force; refused without the solver's local region.
  const std::string base =
      "ctsurg_scenario: 1\nmodel: {kind: fem, tetmesh: t.h5, solver: static}\nmaterial: {preset: kidney}\ntime: {duration_s: 1}\n"
      "output: {trajectory: o.h5}\ntools:\n  - grab: {radius_mm: 2, local_region_mm: 12, path: [{t: 0, position_mm: [0, 0, 0]}]}\n";
  const Scenario ok = parse_scenario(base + "solver: {local_region: {radius_mm: 20}}\n", "f.yaml", "/b");
  EXPECT_EQ(ok.tools[0].local_region_mm, 12);
  try {
    (void)parse_scenario(base, "f.yaml", "/b");
    ADD_FAILURE() << "a tool's local_region_mm without the solver's local region was accepted";
  } catch (const InputError& err) {
    EXPECT_EQ(err.field(), "tools[0].grab.local_region_mm") << err.what();
  }
}

// Without a local region the engine has no region metrics and no region.
TEST(FemLocalRegion, AbsentLeavesTheEngineAsItWas) {
  FemModel m = region_block();
  FemBoundaryConditions supports = base_fixed(m);
  FemEngineOptions o;
  o.solver = FemSolver::static_equilibrium;
  FemEngine e(std::move(m), std::move(supports), EmbeddedSurface(), {0, 0, 0}, o);
  EXPECT_EQ(e.local_region(), nullptr);
  EXPECT_EQ(e.extra_metrics().size(), 4u);
}

// (d) Refusals name their field.
TEST(FemLocalRegion, BadInputIsRefusedWithTheField) {
  const auto engine_field = [](FemEngineOptions o, FemModel m, FemBoundaryConditions supports) -> std::string {
    try {
      FemEngine e(std::move(m), std::move(supports), EmbeddedSurface(), {0, 0, 0}, o);
    } catch (const InputError& err) {
      EXPECT_EQ(err.file(), "s.yaml");
      return err.field() + ": " + err.what();
    }
    return "(accepted)";
  };
  const FemModel m = region_block();
  for (const double r : {0.0, -2.0, std::numeric_limits<double>::quiet_NaN()})
    EXPECT_EQ(engine_field(local_options(r), m, base_fixed(m)).rfind("local_region: ", 0), 0u) << r;
  FemEngineOptions dynamic = local_options(5);
  dynamic.solver = FemSolver::implicit;
  EXPECT_NE(engine_field(dynamic, m, base_fixed(m)).find("needs solver: static"), std::string::npos);
  {
    const FemBoxMesh box = fem_box_mesh(kRegionCells, kRegionSize);
    FemModel q = build_quadratic_fem_model(box.nodes, box.tets, test::fem_material(FemLaw::neo_hookean));
    FemBoundaryConditions s = base_fixed(q);
    EXPECT_NE(engine_field(local_options(5), std::move(q), s).find("linear (4-node) tets"), std::string::npos);
  }
  // Rollers on the base hold z only: a grab would have to complete them, which the factorised global
  // model cannot take.
  FemBoundaryConditions rollers;
  for (const int32_t i : test::nodes_where(m, 2, 0.0)) rollers.fixed_components.push_back(3 * i + 2);
  EXPECT_NE(engine_field(local_options(5), m, rollers).find("alone must hold"), std::string::npos);
  FemLocalRegionOptions o;
  o.radius_mm = -1;
  try {
    FemLocalRegionSolver bad(m, base_fixed(m), o);
    ADD_FAILURE() << "a negative radius was accepted";
  } catch (const InputError& err) {
    EXPECT_EQ(err.field(), "radius_mm");
  }
  // Scenarios: solver.local_region.radius_mm > 0, solver static, a grab or force tool.
  const std::string base =
      "ctsurg_scenario: 1\nmodel: {kind: fem, tetmesh: t.h5, solver: static}\nmaterial: {preset: kidney}\ntime: {duration_s: 1}\n"
      "output: {trajectory: o.h5}\n";
  const std::string grab = "tools:\n  - grab: {radius_mm: 2, path: [{t: 0, position_mm: [0, 0, 0]}]}\n";
  const auto parse = [](const std::string& text) -> std::string {
    try {
      const Scenario s = parse_scenario(text, "f.yaml", "/b");
      return "(accepted " + std::to_string(s.solver.local_region_mm) + ")";
    } catch (const InputError& err) {
      return err.what();
    }
  };
  EXPECT_EQ(parse(base + grab + "solver: {local_region: {radius_mm: 20}}\n"), "(accepted 20.000000)");
  EXPECT_NE(parse(base + grab + "solver: {local_region: {radius_mm: 0}}\n").find("solver.local_region.radius_mm"), std::string::npos);
  EXPECT_NE(parse(base + grab + "solver: {local_region: {radius_mm: -3}}\n").find("solver.local_region.radius_mm"), std::string::npos);
  EXPECT_NE(parse(base + grab + "solver: {local_region: {}}\n").find("solver.local_region.radius_mm"), std::string::npos);
  EXPECT_NE(parse(base + "solver: {local_region: {radius_mm: 20}}\n").find("solver.local_region: needs a grab or force tool"),
            std::string::npos)
      << parse(base + "solver: {local_region: {radius_mm: 20}}\n");
  std::string implicit = base;
  implicit.replace(implicit.find("solver: static"), 14, "solver: implicit");
  EXPECT_NE(parse(implicit + grab + "solver: {local_region: {radius_mm: 20}}\n").find("solver.local_region: only with solver: static"),
            std::string::npos);
}

}  // namespace
}  // namespace ctsurg::sim
