// Tests for ctsurg/sim/scenario/trajectory_recorder.h with an engine without physics
// (support/fake_engine.h): frames go out in LPS (the local frame plus the origin); without a surface
// the nodes are the point set and its displacement is the nodes'; the metrics are the documented eight
// and then the engine's own; a sphere shows its radius while it acts (a probe while active, a grab
// while it holds something), a blade its edge's ends and whether it is active; particles only on
// request; truncate drops frames after a checkpoint.
#include "ctsurg/sim/scenario/trajectory_recorder.h"

#include "ctsurg/sim/scenario/scenario.h"
#include "fake_engine.h"

#include <gtest/gtest.h>

namespace ctsurg::sim {
namespace {

const char* kScenario = R"(ctsurg_scenario: 1
name: recorded
model: {kind: explicit_springs, grid: grid.h5}
material: {preset: liver}
tools:
  - grab: {radius_mm: 2, start_s: 0.1, path: [{t: 0, position_mm: [100, 200, 300]}]}
  - probe: {radius_mm: 3, end_s: 0.2, path: [{t: 0, position_mm: [110, 200, 300]}, {t: 1, position_mm: [110, 210, 300]}]}
  - cut: {blade_edge_mm: [0, 0, 4], path: [{t: 0, position_mm: [105, 195, 300]}]}
time: {duration_s: 1}
output: {trajectory: out.h5, frame_interval_s: 0.1, particles: true}
)";

TEST(TrajectoryRecorder, FramesMetricsAndToolsAsDocumented) {
  const Scenario s = parse_scenario(kScenario, "s.yaml", ".");
  test::FakeEngine engine(0.01);
  const ToolTimeline timeline(s.tools, engine.rest_positions(), engine.origin());
  TrajectoryRecorder r(s, engine, timeline, {}, 11);
  r.record(engine, timeline, 0.0);
  (void)engine.step({}, 15);          // t = 0.15: the grab's window is open, the probe's too
  engine.engaged_tools = {0};         // the grab holds something
  r.record(engine, timeline, 0.15);
  (void)engine.step({}, 10);          // t = 0.25: the probe's window closed
  r.record(engine, timeline, 0.25);
  EXPECT_EQ(r.frames(), 3u);
  const Trajectory t = r.finish(engine.dt());
  EXPECT_EQ(t.scenario, "recorded");
  EXPECT_EQ(t.model, "explicit_springs (grid)");
  EXPECT_EQ(t.dt_s, 0.01);
  // No surface: the nodes, in LPS.
  EXPECT_EQ(t.rest_vertices, (std::vector<float>{100, 200, 300, 101, 200, 300}));
  EXPECT_EQ(t.rest_particles, t.rest_vertices);
  ASSERT_EQ(t.frame_count(), 3);
  EXPECT_FLOAT_EQ(t.frame_vertices(1)[3], 101.15f);
  EXPECT_EQ(t.particles.size(), 3u * 6);
  EXPECT_EQ(t.topologies.size(), 1u);
  EXPECT_TRUE(t.topologies[0].empty());
  // Metrics: the eight, then the engine's.
  const std::vector<std::string> names{"kinetic_energy", "elastic_energy", "max_displacement", "surface_max_displacement",
                                       "enclosed_volume", "surface_area", "springs_cut", "dt", "calls"};
  ASSERT_EQ(t.metrics.size(), names.size());
  for (size_t k = 0; k < names.size(); ++k) {
    EXPECT_EQ(t.metrics[k].name, names[k]);
    EXPECT_EQ(t.metrics[k].values.size(), 3u);
  }
  EXPECT_NEAR(t.metric("max_displacement")->values[1], 0.15, 1e-12);
  EXPECT_EQ(t.metric("surface_max_displacement")->values, t.metric("max_displacement")->values);
  EXPECT_EQ(t.metric("enclosed_volume")->values[2], 0.0);
  EXPECT_EQ(t.metric("calls")->values[2], 2.0);
  // Spheres: grab (inactive, then holding), probe (active, then past its window).
  EXPECT_EQ(t.sphere_kinds, (std::vector<std::string>{"grab", "probe"}));
  ASSERT_EQ(t.spheres.size(), 3u * 2 * 4);
  EXPECT_EQ(t.spheres[3], 0.0);       // frame 0 grab: not yet
  EXPECT_EQ(t.spheres[7], 3.0);       // frame 0 probe: active
  EXPECT_EQ(t.spheres[8 + 3], 2.0);   // frame 1 grab: holding
  EXPECT_NEAR(t.spheres[8 + 4 + 1], 201.5, 1e-9);  // the probe at 0.15 s, LPS
  EXPECT_EQ(t.spheres[16 + 7], 0.0);  // frame 2 probe: ended
  // The blade: its edge's ends and active.
  ASSERT_EQ(t.blade_count(), 1);
  EXPECT_EQ((std::vector<double>(t.blades.begin(), t.blades.begin() + 7)), (std::vector<double>{105, 195, 298, 105, 195, 302, 1}));
}

TEST(TrajectoryRecorder, TruncateDropsTheFramesAfterACheckpoint) {
  const Scenario s = parse_scenario(kScenario, "s.yaml", ".");
  test::FakeEngine engine(0.01);
  const ToolTimeline timeline(s.tools, engine.rest_positions(), engine.origin());
  TrajectoryRecorder r(s, engine, timeline, {}, 11);
  for (int f = 0; f < 4; ++f) {
    r.record(engine, timeline, 0.1 * f);
    (void)engine.step({}, 10);
  }
  r.truncate(2);
  r.record(engine, timeline, 0.2);
  const Trajectory t = r.finish(0.005);
  EXPECT_EQ(t.frame_count(), 3);
  EXPECT_EQ(t.time, (std::vector<double>{0.0, 0.1, 0.2}));
  EXPECT_EQ(t.vertices.size(), 3u * 6);
  EXPECT_EQ(t.blades.size(), 3u * 7);
  EXPECT_EQ(t.spheres.size(), 3u * 2 * 4);
  for (const auto& m : t.metrics) EXPECT_EQ(m.values.size(), 3u) << m.name;
  validate_trajectory(t, "truncated");
}

}  // namespace
}  // namespace ctsurg::sim
