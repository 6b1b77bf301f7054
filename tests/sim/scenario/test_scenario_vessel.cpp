// kind: vessel scenarios (scenario.h, scenario_engine.cpp; sim/vessel): a centerline written to a file
// in the test, pulled and bent by a grab, twisted, clamped and cut; the clamp tool and grab rotations
// for every model; the refusals (a grab that captures no atom, a missing wall thickness, fields of
// other models, grab rotations elsewhere).
#include "ctsurg/core/centerline_file.h"
#include "ctsurg/core/error.h"
#include "ctsurg/sim/scenario/scenario.h"
#include "ctsurg/sim/scenario/scenario_model.h"
#include "ctsurg/sim/scenario/scenario_run.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <string>

namespace {

using namespace ctsurg::sim;
using ctsurg::test::TempDir;

// A 40 mm vessel along x from (100, -50, 20) LPS, points 1 mm apart, radius 1.5 mm: dir/vessel.h5.
void write_vessel(const std::filesystem::path& dir) {
  ctsurg::Centerline c;
  for (int i = 0; i <= 40; ++i) {
    c.points.insert(c.points.end(), {100.0 + i, -50.0, 20.0});
    c.radius.push_back(1.5);
  }
  c.branch_offsets = {0, 41};
  c.branch_nodes = {0, 1};
  c.nodes = {100, -50, 20, 140, -50, 20};
  ctsurg::write_centerline_file(dir / "vessel.h5", c, ctsurg::test::test_provenance());
}

std::string vessel_scenario(const std::string& tools, const std::string& vessel = "vessel:\n  wall_thickness_mm: 0.3\n") {
  return "ctsurg_scenario: 1\n"
         "model:\n  kind: vessel\n  centerline: vessel.h5\n" +
         vessel +
         "material:\n  youngs_modulus_pa: 1.0e6\n  poisson_ratio: 0.45\n  density_g_per_cm3: 1.06\n  damping_per_s: 10\n"
         "fixed:\n  - box: {min: [99, -51, 19], max: [101.5, -49, 21]}\n" +
         tools + "time:\n  duration_s: 0.5\noutput:\n  trajectory: out.h5\n  frame_interval_s: 0.1\n";
}

TEST(ScenarioVessel, AGrabPullsAndTwistsAClampedVessel) {
  TempDir dir;
  write_vessel(dir.path());
  const std::string tools =
      "tools:\n"
      "  - grab:\n      radius_mm: 2.5\n      end_s: 0.4\n      path:\n"
      "        - {t: 0, position_mm: [138, -50, 20]}\n"
      "        - {t: 0.3, offset_mm: [0, 0, 10], rotation: {axis: [1, 0, 0], angle_deg: 60}}\n";
  const Scenario s = parse_scenario(vessel_scenario(tools), dir.path() / "s.yaml", dir.path());
  EXPECT_EQ(s.model, ModelKind::vessel);
  EXPECT_TRUE(model_inputs(s).centerline);
  EXPECT_FALSE(model_inputs(s).grid);
  const auto described = nlohmann::json::parse(describe_scenario(s));
  EXPECT_EQ(described["inputs"]["centerline"], (dir.path() / "vessel.h5").string());
  EXPECT_EQ(described["model"], "vessel");
  RunReport report;
  const ctsurg::Trajectory t = run_scenario(s, &report);
  EXPECT_EQ(t.model, "vessel (rmf)");
  EXPECT_EQ(report.particles, 41);
  EXPECT_EQ(report.fixed, 2);
  EXPECT_EQ(t.vertex_count(), 41 * 16);
  EXPECT_EQ(t.frame_count(), 6);
  const auto metric = [&](const std::string& name) {
    for (const auto& m : t.metrics)
      if (m.name == name) return m.values;
    ADD_FAILURE() << name;
    return std::vector<double>{};
  };
  // Lifted 10 mm at 0.3 s (the grab's centre), let go at 0.4 s.
  EXPECT_GT(metric("max_displacement")[3], 9.0);
  EXPECT_GT(metric("chain_length")[3], 40.0);
  EXPECT_LT(metric("max_displacement")[5], metric("max_displacement")[3]);
  EXPECT_GT(metric("enclosed_volume")[0], 0.95 * 3.14159 * 1.5 * 1.5 * 40);
}

TEST(ScenarioVessel, AClampHoldsWhileABladeCutsTheVesselInTwo) {
  TempDir dir;
  write_vessel(dir.path());
  const std::string tools =
      "gravity_mm_per_s2: [0, 0, -9810]\n"
      "tools:\n"
      "  - clamp: {radius_mm: 1.2, position_mm: [130, -50, 20]}\n"
      "  - cut:\n      blade_edge_mm: [0, 0, 6]\n      start_s: 0.1\n      end_s: 0.2\n      path:\n"
      "        - {t: 0.1, position_mm: [120.5, -55, 20]}\n        - {t: 0.2, position_mm: [120.5, -45, 20]}\n";
  const Scenario s = parse_scenario(vessel_scenario(tools), dir.path() / "s.yaml", dir.path());
  ASSERT_STREQ(s.tools[0].kind(), "clamp");
  EXPECT_EQ(s.tools[0].acts(), ToolPrimitive::hold);  // a grab that stays where it is put
  EXPECT_EQ(s.tools[0].path.size(), 1u);
  EXPECT_EQ(s.tools[0].label, "tools[0] (clamp)");
  RunReport report;
  const ctsurg::Trajectory t = run_scenario(s, &report);
  EXPECT_EQ(report.springs_cut, 1);
  EXPECT_GT(t.topologies.size(), 1u);  // the cut changed the surface
  // The clamp's ring (x = 130) stays put; the piece cut free of it (x = 100 to 120, a 20 mm cantilever
  // from the fixed end) sags under gravity, which the clamp prevented before the cut.
  const float* last = t.frame_vertices(t.frame_count() - 1);
  const float* rest = t.rest_vertices.data();
  const size_t clamp_ring = 3 * 30 * 16, cut_end_ring = 3 * 20 * 16;
  EXPECT_NEAR(last[clamp_ring + 2], rest[clamp_ring + 2], 1e-3);
  EXPECT_LT(last[cut_end_ring + 2], rest[cut_end_ring + 2] - 0.1);
}

TEST(ScenarioVessel, Refusals) {
  TempDir dir;
  write_vessel(dir.path());
  const auto fails = [&](const std::string& text, const std::string& needle) {
    try {
      const Scenario s = parse_scenario(text, dir.path() / "s.yaml", dir.path());
      (void)run_scenario(s);
      ADD_FAILURE() << "accepted: " << needle;
    } catch (const ctsurg::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  // A grab 10 mm off the centerline captures no atom: the error names the tool.
  fails(vessel_scenario("tools:\n  - grab: {radius_mm: 2, path: [{t: 0, position_mm: [120, -40, 20]}]}\n"), "tools[0] (grab)");
  fails(vessel_scenario("", "vessel:\n  spokes: 8\n"), "wall_thickness_mm");
  fails(vessel_scenario("", ""), "vessel");
  fails(vessel_scenario("tools:\n  - instrument: {mesh: x.stl, path: [{t: 0, position_mm: [0, 0, 0]}]}\n"), "not supported by kind: vessel");
  fails(vessel_scenario("") + "backend: cuda\n", "backend");
  // Grab rotations: refused for the other models, naming the field.
  const std::string grid_scenario =
      "ctsurg_scenario: 1\nmodel:\n  kind: spring_grid\n  grid: grid.h5\nmaterial:\n  preset: liver\n"
      "tools:\n  - grab: {radius_mm: 2, path: [{t: 0, position_mm: [0, 0, 0]}, {t: 0.1, offset_mm: [0, 0, 1], "
      "rotation: {axis: [1, 0, 0], angle_deg: 30}}]}\n"
      "time:\n  duration_s: 0.5\noutput:\n  trajectory: out.h5\n";
  fails(grid_scenario, "tools[0].grab.path[1].rotation");
  // A clamp parses for every model (a still grab).
  const Scenario clamp = parse_scenario(
      "ctsurg_scenario: 1\nmodel:\n  kind: spring_grid\n  grid: grid.h5\nmaterial:\n  preset: liver\n"
      "tools:\n  - clamp: {radius_mm: 2, at_fraction: [0.5, 0.5, 0.5], start_s: 0.1, end_s: 0.3}\n"
      "time:\n  duration_s: 0.5\noutput:\n  trajectory: out.h5\n",
      dir.path() / "s.yaml", dir.path());
  EXPECT_STREQ(clamp.tools[0].kind(), "clamp");
  EXPECT_EQ(clamp.tools[0].start_s, 0.1);
  EXPECT_EQ(clamp.tools[0].path[0].t, 0.1);
  // A model section's fields of other models.
  fails("ctsurg_scenario: 1\nmodel:\n  kind: vessel\n  centerline: vessel.h5\n  grid: grid.h5\nvessel: {wall_thickness_mm: 0.3}\n"
        "material: {preset: liver}\ntime: {duration_s: 1}\noutput: {trajectory: o.h5}\n",
        "model.grid");
}

}  // namespace
