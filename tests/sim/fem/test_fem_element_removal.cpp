// Tests for ctsurg/sim/fem/fem_element_removal.h and the FEM engine's remove primitive (a cautery) on an
// 8 x 2 x 2 mm bar of Kuhn tets (1 mm cells, 6 tets each, 1/6 mm^3 a tet) fixed at x = 0: the elements
// whose centroid is inside the tip go nearest first as far as the budget lasts; the model without them
// keeps its nodes (the orphans massless) and materials; the engine spends rate x dt a step, its
// element volume drops by what it counts as removed, its boundary shows the crater, and what it cannot
// do (a static solver, a blade beside it) is refused naming the tool.
#include "ctsurg/sim/fem/fem_element_removal.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/fem/fem_engine.h"
#include "fem_test_models.h"
#include "tool_inputs.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ctsurg::sim {
namespace {

const std::array<int, 3> kBarCells{8, 2, 2};
const std::array<double, 3> kBarSize{8, 2, 2};

TEST(FemElementRemoval, NearestFirstWhileTheBudgetLasts) {
  const FemModel m = test::fem_box_model(FemLaw::linear, kBarCells, kBarSize);
  const std::vector<double> u(m.nodes.size(), 0.0);
  // A 0.6 mm tip at the free end's corner cell centre: the 6 tets of that cell have their centroids
  // within 0.6 mm of it; 3.5 tets of budget takes the 3 nearest.
  const Sphere tip{{7.5, 0.5, 0.5}, 0.6};
  double budget = 3.5 / 6.0;
  FemElementRemoval r = fem_elements_in_sphere(m, u, tip, &budget);
  ASSERT_EQ(r.elements.size(), 3u);
  EXPECT_NEAR(r.volume_mm3, 0.5, 1e-12);
  EXPECT_NEAR(budget, 0.5 / 6.0, 1e-12);
  EXPECT_FALSE(r.exhausted);
  // Nearest first.
  const auto centroid_distance = [&](int32_t e) {
    double d = 0;
    for (int k = 0; k < 3; ++k) {
      double c = 0;
      for (int a = 0; a < 4; ++a) c += 0.25 * m.nodes[3 * static_cast<size_t>(m.tets[4 * static_cast<size_t>(e) + a]) + k];
      d += (c - tip.centre[static_cast<size_t>(k)]) * (c - tip.centre[static_cast<size_t>(k)]);
    }
    return std::sqrt(d);
  };
  EXPECT_LE(centroid_distance(r.elements[0]), centroid_distance(r.elements[1]));
  EXPECT_LE(centroid_distance(r.elements[1]), centroid_distance(r.elements[2]));
  budget = 100;
  r = fem_elements_in_sphere(m, u, tip, &budget);
  EXPECT_EQ(r.elements.size(), 6u);
  EXPECT_TRUE(r.exhausted);
}

TEST(FemElementRemoval, TheModelWithoutThemKeepsItsNodesAndMaterials) {
  FemModel m = test::fem_box_model(FemLaw::linear, kBarCells, kBarSize);
  // Two materials: the second on the last cell's elements.
  m.materials.push_back(m.materials[0]);
  m.materials[1].youngs_modulus *= 2;
  m.element_material.assign(static_cast<size_t>(m.tet_count()), 0);
  std::vector<uint8_t> removed(static_cast<size_t>(m.tet_count()), 0);
  const std::vector<double> u(m.nodes.size(), 0.0);
  double budget = 100;
  const FemElementRemoval r = fem_elements_in_sphere(m, u, {{7.5, 0.5, 0.5}, 0.6}, &budget);
  for (const int32_t e : r.elements) removed[static_cast<size_t>(e)] = 1;
  m.element_material[static_cast<size_t>(m.tet_count() - 1)] = 1;  // the last element keeps material 1
  ASSERT_FALSE(removed[static_cast<size_t>(m.tet_count() - 1)]) << "pick a kept element for the material check";
  m = build_fem_model(m.nodes, m.tets, m.materials, m.element_material);
  const FemModel w = fem_model_without(m, removed);
  EXPECT_EQ(w.node_count(), m.node_count());
  EXPECT_EQ(w.tet_count(), m.tet_count() - 6);
  EXPECT_EQ(w.element_material.back(), 1);
  // The corner node (8, 0, 0) belonged to that cell only: no element uses it now, it has no mass.
  const int32_t corner = test::nodes_where(m, 0, 8.0)[0];
  EXPECT_EQ(w.node_mass[static_cast<size_t>(corner)], 0.0);
  EXPECT_EQ(w.unused_nodes, 1);
  EXPECT_THROW(fem_model_without(m, std::vector<uint8_t>(3, 0)), InputError);
}

FemEngine dynamic_bar(FemSolver solver = FemSolver::dynamic) {
  FemModel m = test::fem_box_model(FemLaw::neo_hookean, kBarCells, kBarSize);
  FemEngineOptions o;
  o.solver = solver;
  o.mass_damping = 200;
  o.where = "s.yaml";
  FemBoundaryConditions supports;
  supports.fixed_nodes = test::nodes_where(m, 0, 0.0);
  return FemEngine(std::move(m), std::move(supports), EmbeddedSurface(), {0, 0, 0}, o);
}

ToolInput cautery(const Vec3& centre, double rate, bool active = true) { return test::cautery_input(centre, 1.0, rate, active); }

double element_volume(const FemEngine& e) {
  const auto names = e.extra_metrics();
  const EngineMetrics m = e.metrics();
  for (size_t k = 0; k < names.size(); ++k)
    if (names[k].first == "element_volume") return m.extra[k];
  ADD_FAILURE() << "no element_volume metric";
  return 0;
}

TEST(FemEngineCautery, RemovesElementsAtItsRateAndTheVolumeFollows) {
  FemEngine e = dynamic_bar();
  const int64_t elements = e.counts().elements;
  const size_t boundary = e.triangles().size();
  const double volume0 = element_volume(e);
  // 1.3 tets (1/6 mm^3 each) a step: floor(1.3 k) after k steps (about 20 tets have their centroid
  // within the tip's 1 mm).
  const double rate = 1.3 / 6.0 / e.dt();
  const ToolInput tip = cautery({7.5, 1.0, 1.0}, rate);
  ASSERT_TRUE(e.step({tip}, 1).stable);
  EXPECT_NEAR(e.metrics().removed_volume, 1.0 / 6.0, 1e-12);
  EXPECT_EQ(e.counts().elements, elements - 1);
  ASSERT_TRUE(e.step({tip}, 4).stable);
  EXPECT_NEAR(e.metrics().removed_volume, 1.0, 1e-12);  // 6 tets after 5 steps of 1.3
  EXPECT_EQ(e.counts().elements, elements - 6);
  e.sync();
  EXPECT_NEAR(element_volume(e), volume0 - 1.0, 1e-3);  // deformed volume: the bar barely moved
  // Without a surface the model draws its tets' boundary: the crater's walls are in it.
  EXPECT_NE(e.triangles().size(), boundary);
  // Off: the budget is dropped; nothing more goes.
  ASSERT_TRUE(e.step({cautery({7.5, 1.0, 1.0}, rate, false)}, 5).stable);
  EXPECT_NEAR(e.metrics().removed_volume, 1.0, 1e-12);
  // The bar still moves as a whole: a grab of the free end after the removal pulls it.
  for (int k = 0; k < 50; ++k) {
    ToolInput g = test::sphere_tool_input(ToolPrimitive::hold, "grab", {8, 2, 2 + 0.002 * k}, 0.6, true, 1);
    g.start_centre = {8, 2, 2};
    ASSERT_TRUE(e.step({cautery({7.5, 1.0, 1.0}, rate, false), g}, 1).stable);
  }
  EXPECT_TRUE(e.engaged(1));
}

TEST(FemEngineCautery, WhatItCannotDoIsRefusedNamingTheTool) {
  const auto refusal = [](FemEngine& e, const std::vector<ToolInput>& tools) -> std::string {
    try {
      if (e.quasi_static()) {
        e.equilibrium(tools, 0.1);
      } else {
        (void)e.step(tools, 1);
      }
    } catch (const InputError& err) {
      return std::string(err.field()) + ": " + err.problem();
    }
    return "(accepted)";
  };
  FemEngine implicit = dynamic_bar(FemSolver::implicit);
  EXPECT_NE(refusal(implicit, {cautery({7.5, 1, 1}, 10)}).find("tools[0] (cautery): cautery needs solver: dynamic"), std::string::npos);
  FemEngine dynamic = dynamic_bar();
  ToolInput blade;
  blade.acts = ToolPrimitive::separate;
  blade.name = "cut";
  blade.label = "tools[1] (cut)";
  blade.blade_edge_mm = {0, 0, 4};
  EXPECT_NE(refusal(dynamic, {cautery({7.5, 1, 1}, 10), blade}).find("cautery and a blade on one FEM model are not supported (tools[1] (cut))"),
            std::string::npos);
}

}  // namespace
}  // namespace ctsurg::sim
