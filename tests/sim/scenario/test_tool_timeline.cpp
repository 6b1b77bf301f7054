// Tests for ctsurg/sim/scenario/tool_timeline.h: keyframes given as LPS positions, bounding-box
// fractions or offsets become points of the run's frame and the tool moves linearly between them;
// snap_to_tissue puts the path's start on the nearest rest particle; a window opens at start_s (to
// 1e-12 s) and closes at end_s; idle intervals are those no window touches; a blade sweeps once it
// moved the engine's shortest sweep or reaches a keyframe or its end, never across a keyframe, and a
// copy of the timeline replays the same sweeps (a restart's checkpoint).
#include "ctsurg/sim/scenario/tool_timeline.h"

#include "ctsurg/core/error.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ctsurg::sim {
namespace {

// Rest positions of 8 particles at the corners of [0, 10] x [0, 20] x [0, 30] mm (local frame).
std::vector<double> box_corners() {
  std::vector<double> r;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) r.insert(r.end(), {10.0 * i, 20.0 * j, 30.0 * k});
  return r;
}

Keyframe key(double t, PointSpec::Kind kind, const Vec3& v) { return {t, {kind, v}, std::nullopt}; }

ToolAction tool(const char* kind, std::vector<Keyframe> path, double start, double end) {
  ToolAction a;
  a.type = &tool_type(kind);
  a.label = std::string("tools[0] (") + kind + ")";
  a.radius_mm = 2;
  a.path = std::move(path);
  a.start_s = start;
  a.end_s = end;
  return a;
}

void expect_near(const Vec3& a, const Vec3& b) {
  for (size_t c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], 1e-12) << "component " << c;
}

TEST(ToolTimeline, KeyframesBecomePointsOfTheRunsFrameAndTheToolMovesLinearly) {
  const std::vector<ToolAction> tools{tool("grab",
                                           {key(0.1, PointSpec::Kind::position_mm, {105, 210, 330}),
                                            key(0.3, PointSpec::Kind::offset_mm, {0, 0, 4}),
                                            key(0.5, PointSpec::Kind::at_fraction, {1, 0.5, 0})},
                                           0.1, 1.0)};
  const ToolTimeline t(tools, box_corners(), {100, 200, 300});
  ASSERT_EQ(t.size(), 1u);
  expect_near(t.position(0, 0.0), {5, 10, 30});   // before the first keyframe: there
  expect_near(t.position(0, 0.1), {5, 10, 30});   // LPS minus the origin
  expect_near(t.position(0, 0.2), {5, 10, 32});   // halfway to the offset
  expect_near(t.position(0, 0.3), {5, 10, 34});
  expect_near(t.position(0, 0.5), {10, 10, 0});   // the box's fractions
  expect_near(t.position(0, 9.0), {10, 10, 0});   // after the last: there
}

TEST(ToolTimeline, SnapMovesThePathOntoTheNearestRestParticle) {
  ToolAction a = tool("grab", {key(0, PointSpec::Kind::at_fraction, {0.9, 0.1, 0.8}),
                                       key(1, PointSpec::Kind::offset_mm, {0, 5, 0})}, 0, 1);
  a.snap_to_tissue = true;
  std::vector<std::string> notes;
  const ToolTimeline t({a}, box_corners(), {0, 0, 0}, [&](const std::string& n) { notes.push_back(n); });
  expect_near(t.position(0, 0), {10, 0, 30});  // (9, 2, 24) is nearest the corner (10, 0, 30)
  expect_near(t.position(0, 1), {10, 5, 30});  // the whole path moved with it
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("tools[0] (grab): path snapped to tissue by 6.403124 mm"), std::string::npos) << notes[0];
}

TEST(ToolTimeline, WindowsAndIdleIntervals) {
  const std::vector<ToolAction> tools{tool("probe", {key(0, PointSpec::Kind::position_mm, {0, 0, 0})}, 0.2, 0.4)};
  const ToolTimeline t(tools, box_corners(), {0, 0, 0});
  EXPECT_FALSE(t.active(0, 0.19));
  EXPECT_TRUE(t.active(0, 0.2 - 1e-13));  // a step landing on start_s in floating point starts it
  EXPECT_TRUE(t.active(0, 0.3));
  EXPECT_FALSE(t.active(0, 0.4));
  EXPECT_TRUE(t.idle(0.0, 0.19));
  EXPECT_FALSE(t.idle(0.0, 0.2));
  EXPECT_FALSE(t.idle(0.3, 0.35));
  EXPECT_TRUE(t.idle(0.4, 1.0));
  std::vector<ToolInput> in;
  ToolTimeline copy = t;
  copy.inputs(0.25, 0.3, 0.1, in);
  ASSERT_EQ(in.size(), 1u);
  EXPECT_EQ(in[0].acts, ToolPrimitive::push_sphere);
  EXPECT_EQ(in[0].label, "tools[0] (probe)");
  EXPECT_TRUE(in[0].active);
  EXPECT_EQ(in[0].start_s, 0.2);
  EXPECT_EQ(in[0].radius_mm, 2);
  EXPECT_TRUE(in[0].sweeps.empty());
}

TEST(ToolTimeline, BladeSweepsOnStraightStretchesOnceItMovedFarEnough) {
  // From (0, 0, 0) to (8, 0, 0) by t = 0.5 s (16 mm/s), then to (8, 4, 0) by 1 s (8 mm/s); active
  // 0.125 .. 0.875 s; steps of 3/32 s (every time here is exact in binary), shortest sweep 2.5 mm.
  ToolAction blade = tool("cut",
                          {key(0.0, PointSpec::Kind::position_mm, {0, 0, 0}), key(0.5, PointSpec::Kind::position_mm, {8, 0, 0}),
                           key(1.0, PointSpec::Kind::position_mm, {8, 4, 0})},
                          0.125, 0.875);
  blade.blade_edge_mm = {0, 0, 5};
  ToolTimeline t({blade}, box_corners(), {0, 0, 0});
  const ToolTimeline checkpoint = t;
  const auto run = [](ToolTimeline& tl) {
    std::vector<std::array<Vec3, 2>> out;
    std::vector<ToolInput> in;
    for (double s = 0; s < 1.0; s += 3.0 / 32) {
      tl.inputs(s, s + 3.0 / 32, 2.5, in);
      EXPECT_EQ(in[0].blade_edge_mm, (Vec3{0, 0, 5}));
      out.insert(out.end(), in[0].sweeps.begin(), in[0].sweeps.end());
    }
    return out;
  };
  const auto all = run(t);
  // The first sweep starts where the window opens (x = 2 at 0.125 s) and waits until the blade moved
  // 2.5 mm; the step across the keyframe at 0.5 s sweeps up to it and goes on from there (its rest is
  // too short to sweep yet); the last sweep ends at end_s however short it is.
  const std::vector<std::array<Vec3, 2>> expected{
      {Vec3{2, 0, 0}, Vec3{4.5, 0, 0}},  {Vec3{4.5, 0, 0}, Vec3{7.5, 0, 0}},   {Vec3{7.5, 0, 0}, Vec3{8, 0, 0}},
      {Vec3{8, 0, 0}, Vec3{8, 2.75, 0}}, {Vec3{8, 2.75, 0}, Vec3{8, 3, 0}}};
  EXPECT_EQ(all, expected);
  // A copy (a restart's checkpoint) replays the same sweeps.
  ToolTimeline replay = checkpoint;
  EXPECT_EQ(run(replay), expected);
}

TEST(ToolTimeline, AnInstrumentTurnsBySlerpAndCarriesItsShape) {
  // Keys at 0 (no rotation given: the identity), 1 s (90 degrees about z) and 2 s (none: held): the
  // inputs carry the loaded instrument and the rotation slerped on the same time fraction as the path.
  ToolAction a = tool("instrument",
                      {key(0, PointSpec::Kind::position_mm, {0, 0, 0}), key(1, PointSpec::Kind::offset_mm, {10, 0, 0}),
                       key(2, PointSpec::Kind::offset_mm, {10, 0, 0})},
                      0, 3);
  a.path[1].rotation = axis_angle_rotation({0, 0, 1}, 90, "t", "r");
  a.instrument_mesh = std::filesystem::path(CTSURG_SOURCE_DIR) / "data_samples" / "instruments" / "probe_rod.stl";
  std::vector<std::string> notes;
  ToolTimeline t({a}, box_corners(), {0, 0, 0}, [&](const std::string& n) { notes.push_back(n); });
  ASSERT_TRUE(t.instrument(0));
  EXPECT_NE(notes.at(0).find("distance grid"), std::string::npos);
  EXPECT_NEAR(rotation_angle_deg(t.orientation(0, 0.5)), 45, 1e-9);
  EXPECT_NEAR(rotation_angle_deg(t.orientation(0, 1.5)), 90, 1e-9);
  std::vector<ToolInput> in;
  t.inputs(0.2, 0.25, 0.1, in);
  ASSERT_EQ(in.size(), 1u);
  EXPECT_EQ(in[0].instrument, t.instrument(0));
  EXPECT_NEAR(rotation_angle_deg(in[0].orientation), 22.5, 1e-9);
  expect_near(in[0].centre, {2.5, 0, 0});
  // A mesh that is not there: the file is named.
  a.instrument_mesh = "/nonexistent/jaw.ply";
  try {
    ToolTimeline bad({a}, box_corners(), {0, 0, 0});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/jaw.ply"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ctsurg::sim
