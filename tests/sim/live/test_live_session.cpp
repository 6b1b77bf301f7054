// Tests for ctsurg/sim/live/live_session.h on the scenario tests' bar of tissue (grid, surface and tet
// mesh files): a grab dragged across the bar, a cut, a probe, FEM grabs (dynamic and quasi-static) and
// an FEM cut between batched steps, each saved and replayed through run_scenario (in-process) and the
// ctsurg-sim tool to the same trajectory, bit for bit; pause, resume, reset and real-time advancing; step
// halvings while dragging; a jump that makes the model unstable and a grab on empty space, reported
// with the guard's (or the engine's) message, the session back at the frame before; a move travelling
// over its ramp, and a ramp cut at the frame a stopped session goes back to; the binary frames
// of the session (live_protocol.h) carrying the triangles only when a cut changed them.
#include "ctsurg/sim/live/live_session.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/trajectory_file.h"
#include "ctsurg/sim/live/live_protocol.h"
#include "ctsurg/sim/scenario/scenario.h"
#include "ctsurg/sim/scenario/scenario_run.h"
#include "live_test_scenarios.h"
#include "scenario_test_files.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;
using namespace ctsurg;
using namespace ctsurg::sim;
using ctsurg::test::run_tool;
using ctsurg::test::TempDir;
using ctsurg::sim::test::expect_same_trajectory;
using ctsurg::sim::test::live_bar_text;

namespace {

std::string fem_text(const std::string& solver) {
  return "ctsurg_scenario: 1\nname: live fem bar\nmodel:\n  kind: fem\n  tetmesh: tetmesh.h5\n  surface: surface.h5\n"
         "  solver: " + solver + "\nmaterial:\n  law: neo_hookean\n  youngs_modulus_pa: 20000\n  poisson_ratio: 0.3\n"
         "  damping_per_s: 200\nfixed:\n  - box: {min: [10, -20, 30], max: [11.5, 0, 40]}\n"
         "time:\n  duration_s: 1\noutput:\n  trajectory: out.h5\n  frame_interval_s: 0.01\n";
}

LiveSession session_of(const fs::path& dir, const std::string& text) {
  return LiveSession(parse_scenario(text, dir / "s.yaml", dir), text);
}

// Saves the session into dir and replays the saved scenario through run_scenario and ctsurg-sim: both
// must give the session's trajectory.
void expect_replays(const LiveSession& session, const fs::path& dir, const std::string& stem) {
  const fs::path yaml = dir / (stem + ".yaml"), saved = dir / (stem + ".h5"), tool = dir / (stem + "_tool.h5");
  session.save(yaml, saved);
  const Trajectory live = session.trajectory();
  RunReport report;
  const Trajectory replay = run_scenario(read_scenario_file(yaml), &report);
  expect_same_trajectory(live, replay);
  expect_same_trajectory(live, read_trajectory_file(saved));
  const auto r = run_tool("ctsurg-sim", {yaml.string(), "-o", tool.string(), "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  expect_same_trajectory(live, read_trajectory_file(tool));
}

double max_surface_move(const Trajectory& t, int64_t frame) {
  const float* v = t.frame_vertices(frame);
  double worst = 0;
  for (int64_t i = 0; i < 3 * t.vertex_count(); ++i) {
    worst = std::max(worst, std::abs(double(v[i]) - t.rest_vertices[static_cast<size_t>(i)]));
  }
  return worst;
}

}  // namespace

TEST(LiveSession, AGrabDraggedAcrossTheBarReplaysBitForBit) {
  TempDir dir;
  ctsurg::sim::test::write_block_files(dir.path(), 16, 4, 4, 2.0);
  LiveSession session = session_of(dir.path(), live_bar_text());
  EXPECT_EQ(session.frames(), 1);
  session.advance_events(7);  // some steps before the user acts
  const int grab = session.begin_tool({&tool_type("grab"), 2.5, {}, {42, -15, 35}});
  EXPECT_TRUE(session.tool_active(grab));
  // A drag: a move between most steps, two moves (the second wins) before some, none before others.
  for (int k = 1; k <= 80; ++k) {
    session.move_tool(grab, {42, -15 - 0.1 * k, 35 + 0.05 * k});
    if (k % 7 == 0) session.move_tool(grab, {42.1, -15 - 0.1 * k, 35 + 0.05 * k});
    session.advance_events(k % 5 == 0 ? 3 : 1);
  }
  session.end_tool(grab);
  EXPECT_FALSE(session.tool_active(grab));
  EXPECT_THROW(session.move_tool(grab, {42, -15, 35}), InputError);
  session.advance_events(400);
  EXPECT_EQ(session.steps(), 7 + 80 + 16 * 2 + 400);
  const Trajectory live = session.trajectory();
  ASSERT_GE(live.frame_count(), 5);
  ASSERT_EQ(live.sphere_kinds, std::vector<std::string>{"grab"});
  // The grab moved the free end by mm while it held (the largest surface move over the frames).
  double moved = 0;
  for (int64_t f = 0; f < live.frame_count(); ++f) moved = std::max(moved, max_surface_move(live, f));
  EXPECT_GT(moved, 4.0);
  expect_replays(session, dir.path(), "grab");
  // The saved file names the tool's keyframes as absolute LPS positions with their times.
  std::ifstream in(dir.path() / "grab.yaml");
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_NE(text.str().find("position_mm"), std::string::npos);
  EXPECT_NE(text.str().find("grab:"), std::string::npos);
}

TEST(LiveSession, ACutChangesTheTopologyAndReplaysBitForBit) {
  TempDir dir;
  ctsurg::sim::test::write_block_files(dir.path(), 16, 4, 4, 2.0);
  LiveSession session = session_of(dir.path(), live_bar_text());
  session.advance_events(3);
  const uint64_t before = session.topology_version();
  LiveFrame first = live_frame_of(session, 0, 0);
  EXPECT_TRUE(first.flags & LiveFrame::triangles_follow);
  EXPECT_FALSE(live_frame_of(session, 1, session.topology_version()).flags & LiveFrame::triangles_follow);
  // A blade with a 20 mm edge along z, drawn along y through the bar at x = 27 mm.
  const int blade = session.begin_tool({&tool_type("cut"), 0, {0, 0, 20}, {27, -25, 35}});
  for (int k = 1; k <= 40; ++k) {
    session.move_tool(blade, {27, -25 + 0.5 * k, 35});
    session.advance_events(2);
  }
  session.end_tool(blade);
  session.advance_events(150);
  EXPECT_GT(session.topology_version(), before);
  EXPECT_NE(session.triangles(), first.triangles);
  EXPECT_GT(session.engine().metrics().springs_cut, 40);
  EXPECT_GT(session.engine().metrics().triangles_removed, 0);
  // The next frame sent after the cut carries the new triangles.
  const LiveFrame after = live_frame_of(session, 2, before);
  EXPECT_TRUE(after.flags & LiveFrame::triangles_follow);
  EXPECT_EQ(after.triangles, session.triangles());
  const Trajectory live = session.trajectory();
  EXPECT_GT(live.topologies.size(), 1u);
  EXPECT_EQ(live.blades.size(), static_cast<size_t>(live.frame_count()) * 7);
  expect_replays(session, dir.path(), "cut");
}

TEST(LiveSession, AProbePausesResumesResetsAndKeepsRealTime) {
  TempDir dir;
  ctsurg::sim::test::write_block_files(dir.path(), 16, 4, 4, 2.0);
  LiveSession session = session_of(dir.path(), live_bar_text());
  const int probe = session.begin_tool({&tool_type("probe"), 3, {}, {32, -15, 42.5}});
  for (int k = 1; k <= 30; ++k) {
    session.move_tool(probe, {32, -15, 42.5 - 0.1 * k});
    session.advance_events(4);
  }
  // Paused: nothing advances, events wait.
  session.pause();
  const double t = session.time();
  EXPECT_EQ(session.advance(0.05).events, 0);
  EXPECT_EQ(session.advance_events(10).events, 0);
  EXPECT_EQ(session.time(), t);
  session.resume();
  // Real time: 20 ms of wall time give 20 ms of simulated time, or as much as 20 ms of wall time allow
  // (the backlog dropped) where the model steps slower than real time (this bar does under the
  // sanitizers); never more than the 20 ms asked, whatever the machine's speed.
  const LiveAdvance rt = session.advance(0.02);
  EXPECT_TRUE(rt.sim_s >= 0.02 - 1e-12 || rt.wall_s >= 0.02) << "sim " << rt.sim_s << " s in " << rt.wall_s << " s";
  EXPECT_GT(rt.sim_s, 0);
  EXPECT_LT(rt.sim_s, 0.02 + session.dt() * 1.5);
  session.end_tool(probe);
  session.advance_events(60);
  std::vector<float> now;
  session.surface(now);
  const Trajectory live = session.trajectory();
  double pressed = 0;
  for (int64_t f = 0; f < live.frame_count(); ++f) pressed = std::max(pressed, max_surface_move(live, f));
  EXPECT_GT(pressed, 0.5);  // mm: the probe pushed the top in
  expect_replays(session, dir.path(), "probe");
  // Reset: a new engine at rest, the recording restarted, no tools.
  session.reset();
  EXPECT_EQ(session.time(), 0.0);
  EXPECT_EQ(session.frames(), 1);
  EXPECT_FALSE(session.tool_active(probe));
  session.surface(now);
  const Trajectory fresh = session.trajectory();
  ASSERT_EQ(now.size(), fresh.rest_vertices.size());
  for (size_t i = 0; i < now.size(); ++i) EXPECT_NEAR(now[i], fresh.rest_vertices[i], 1e-4);
  EXPECT_TRUE(fresh.sphere_kinds.empty());
}

TEST(LiveSession, FemGrabsReplayBitForBitDynamicAndQuasiStatic) {
  for (const std::string solver : {"dynamic", "static"}) {
    SCOPED_TRACE(solver);
    TempDir dir;
    ctsurg::sim::test::write_block_files(dir.path(), 16, 4, 4, 2.0);
    ctsurg::sim::test::write_bar_tet_mesh(dir.path());
    LiveSession session = session_of(dir.path(), fem_text(solver));
    session.advance_events(2);  // dynamic: batched to the frames while no tool acts
    const int grab = session.begin_tool({&tool_type("grab"), 4.5, {}, {43, -15, 35}});
    for (int k = 1; k <= 12; ++k) {
      session.move_tool(grab, {43, -15, 35 + 0.25 * k});
      session.advance_events(solver == "static" ? 1 : 20);
    }
    session.end_tool(grab);
    session.advance_events(solver == "static" ? 2 : 30);
    const Trajectory live = session.trajectory();
    ASSERT_GE(live.frame_count(), 3);
    double moved = 0;
    for (int64_t f = 0; f < live.frame_count(); ++f) moved = std::max(moved, max_surface_move(live, f));
    EXPECT_GT(moved, 1.0);
    expect_replays(session, dir.path(), "fem_" + solver);
  }
}

// The status line's "solver error" (LiveSession::solver_error_mm): a quasi-Newton FEM session reports
// each frame's estimate (the engine's metric solver_error_mm, within the frame's budget's reach while
// a grab drags), a Newton one and a spring model none (NaN: the page shows nothing).
TEST(LiveSession, AQuasiNewtonSessionReportsItsSolverError) {
  TempDir dir;
  ctsurg::sim::test::write_block_files(dir.path(), 16, 4, 4, 2.0);
  ctsurg::sim::test::write_bar_tet_mesh(dir.path());
  std::string text = fem_text("static");
  text += "solver: {nonlinear: quasi_newton, tolerance_mm: 0.05}\n";
  LiveSession session = session_of(dir.path(), text);
  session.advance_events(1);
  const int grab = session.begin_tool({&tool_type("grab"), 4.5, {}, {43, -15, 35}});
  double most = 0;
  for (int k = 1; k <= 8; ++k) {
    session.move_tool(grab, {43, -15, 35 + 0.5 * k});
    session.advance_events(1);
    const double e = session.solver_error_mm();
    ASSERT_TRUE(std::isfinite(e)) << "frame " << k;
    EXPECT_GE(e, 0.0);
    most = std::max(most, e);
  }
  EXPECT_GT(most, 0.0);  // an estimate, not a constant
  EXPECT_LT(most, 1.0);  // of a solve converged to 0.05 mm, on a 4 mm drag
  EXPECT_TRUE(std::isnan(session_of(dir.path(), fem_text("static")).solver_error_mm()));
  EXPECT_TRUE(std::isnan(session_of(dir.path(), live_bar_text()).solver_error_mm()));
}

TEST(LiveSession, AnFemCutBetweenBatchedStepsReplaysBitForBit) {
  TempDir dir;
  ctsurg::sim::test::write_block_files(dir.path(), 16, 4, 4, 2.0);
  ctsurg::sim::test::write_bar_tet_mesh(dir.path());
  LiveSession session = session_of(dir.path(), fem_text("dynamic"));
  session.advance_events(1);  // a batch to the first frame
  const uint64_t before = session.topology_version();
  const int blade = session.begin_tool({&tool_type("cut"), 0, {0, 0, 20}, {27.5, -25, 35}});
  for (int k = 1; k <= 20; ++k) {
    session.move_tool(blade, {27.5, -25 + 1.0 * k, 35});
    session.advance_events(5);
  }
  session.end_tool(blade);
  session.advance_events(3);  // batches again once the blade is gone
  EXPECT_GT(session.topology_version(), before);
  EXPECT_GT(session.engine().metrics().triangles_removed, 0);
  expect_replays(session, dir.path(), "fem_cut");
}

TEST(LiveSession, AJumpThatMakesTheModelUnstableGoesBackToTheFrameBefore) {
  TempDir dir;
  ctsurg::sim::test::write_block_files(dir.path(), 16, 4, 4, 2.0);
  LiveSession session = session_of(dir.path(), live_bar_text());
  const int grab = session.begin_tool({&tool_type("grab"), 2.5, {}, {42, -15, 35}});
  for (int k = 1; k <= 20; ++k) {
    session.move_tool(grab, {42, -15 - 0.1 * k, 35});
    session.advance_events(5);
  }
  const int64_t frames = session.frames();
  const Trajectory before = session.trajectory();
  // The held end thrown 60 mm in one step: the guard stops it.
  session.move_tool(grab, {42, -77, 35});
  const LiveAdvance r = session.advance_events(2000);
  ASSERT_TRUE(r.stopped);
  EXPECT_TRUE(session.paused());
  EXPECT_NE(session.stopped_message().find("unstable"), std::string::npos) << session.stopped_message();
  EXPECT_NE(session.stopped_message().find("time.dt_s"), std::string::npos) << session.stopped_message();
  // Back at the last frame before the jump: its surface, its recording.
  EXPECT_GE(session.frames(), frames);
  const Trajectory kept = session.trajectory();
  std::vector<float> now;
  session.surface(now);
  const float* last = kept.frame_vertices(kept.frame_count() - 1);
  for (size_t i = 0; i < now.size(); ++i) ASSERT_EQ(now[i], last[i]) << i;
  EXPECT_EQ(session.time(), kept.time.back());
  for (int64_t f = 0; f < before.frame_count(); ++f) {
    ASSERT_EQ(0, std::memcmp(kept.frame_vertices(f), before.frame_vertices(f), 12 * static_cast<size_t>(before.vertex_count())));
  }
  // The grab still holds (it began before that frame); the session goes on from there and replays.
  EXPECT_TRUE(session.tool_active(grab));
  session.resume();
  EXPECT_TRUE(session.stopped_message().empty());
  session.move_tool(grab, {42, -18, 35.5});
  session.advance_events(120);
  EXPECT_FALSE(session.paused());
  expect_replays(session, dir.path(), "after_unstable");
}

TEST(LiveSession, StepHalvingsWhileDraggingReplayBitForBit) {
  TempDir dir;
  ctsurg::sim::test::write_block_files(dir.path(), 16, 4, 4, 2.0);
  // A step far above the critical one (0.17 ms): the guard fires at the first frames and the session
  // restarts from the last frame with half the step, as ctsurg-sim does; events wait until it is back.
  LiveSession session = session_of(dir.path(), live_bar_text("  dt_s: 0.003\n  max_step_halvings: 6\n"));
  const int grab = session.begin_tool({&tool_type("grab"), 2.5, {}, {42, -15, 35}});
  bool restarted = false;
  for (int k = 1; k <= 150; ++k) {
    session.move_tool(grab, {42, -15 - 0.02 * k, 35});
    restarted |= session.advance_events(1).restarted;
  }
  session.end_tool(grab);
  session.advance_events(300);
  EXPECT_TRUE(restarted);
  EXPECT_GT(session.halvings(), 0);
  EXPECT_LT(session.dt(), 0.003 / 2 * 1.000001);
  EXPECT_FALSE(session.restart_message().empty());
  EXPECT_TRUE(session.stopped_message().empty()) << session.stopped_message();
  expect_replays(session, dir.path(), "halved");
}

TEST(LiveSession, AGrabOnEmptySpaceIsReportedAndDropped) {
  TempDir dir;
  ctsurg::sim::test::write_block_files(dir.path(), 16, 4, 4, 2.0);
  LiveSession session = session_of(dir.path(), live_bar_text());
  session.advance_events(70);  // past the first frame
  const int grab = session.begin_tool({&tool_type("grab"), 2, {}, {42, -15, 60}});
  const LiveAdvance r = session.advance_events(10);
  EXPECT_TRUE(r.stopped);
  EXPECT_NE(session.stopped_message().find("grabs no free particle"), std::string::npos) << session.stopped_message();
  EXPECT_FALSE(session.tool_active(grab));
  EXPECT_TRUE(session.trajectory().sphere_kinds.empty());
  session.resume();
  session.advance_events(100);
  expect_replays(session, dir.path(), "empty_grab");
}

TEST(LiveSession, BadToolsAreRefusedWithTheFieldNamed) {
  TempDir dir;
  ctsurg::sim::test::write_block_files(dir.path(), 16, 4, 4, 2.0);
  LiveSession session = session_of(dir.path(), live_bar_text());
  const auto refused = [&](const LiveToolSpec& spec, const std::string& field) {
    try {
      session.begin_tool(spec);
      ADD_FAILURE() << "accepted, expected a refusal of " << field;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  refused({&tool_type("force"), 2, {}, {30, -15, 35}}, "tool");
  refused({&tool_type("grab"), 0, {}, {30, -15, 35}}, "radius_mm");
  refused({&tool_type("probe"), 51, {}, {30, -15, 35}}, "radius_mm");
  refused({&tool_type("cut"), 0, {0, 0, 0}, {30, -15, 35}}, "blade_edge_mm");
  refused({&tool_type("grab"), 2, {}, {30, std::nan(""), 35}}, "position_mm");
  EXPECT_THROW(session.move_tool(3, {30, -15, 35}), InputError);
  EXPECT_THROW(session.end_tool(-1), InputError);
  // Nothing recorded after the rest frame yet: nothing to save.
  EXPECT_THROW(session.scenario_text("x.h5"), InputError);
}

// A move with a ramp (ctsurg-live: a picture tick) travels to its position over the ramp instead of
// arriving at the next step's end; the session replays bit for bit.
TEST(LiveSession, AMoveTravelsOverItsRampAndReplaysBitForBit) {
  TempDir dir;
  ctsurg::sim::test::write_block_files(dir.path(), 16, 4, 4, 2.0);
  LiveSession session = session_of(dir.path(), live_bar_text());
  EXPECT_THROW(session.set_move_ramp_s(-0.01), InputError);
  EXPECT_THROW(session.set_move_ramp_s(std::nan("")), InputError);
  const double ramp = 0.03;
  session.set_move_ramp_s(ramp);
  EXPECT_EQ(session.move_ramp_s(), ramp);
  const int grab = session.begin_tool({&tool_type("grab"), 2.5, {}, {42, -15, 35}});
  session.advance_events(30);
  // 3 mm in one message: at the next step's end, 17 m/s.
  const double t_move = session.time();
  session.move_tool(grab, {42, -15, 32});
  while (session.time() < t_move + 2 * ramp) ASSERT_FALSE(session.advance_events(1).stopped) << session.stopped_message();
  session.end_tool(grab);
  session.advance_events(50);
  const Trajectory live = session.trajectory();
  ASSERT_EQ(live.sphere_count(), 1);
  int during = 0;
  for (int64_t f = 0; f < live.frame_count(); ++f) {
    const double t = live.time[static_cast<size_t>(f)], z = live.spheres[4 * static_cast<size_t>(f) + 2];
    if (t <= t_move) {
      EXPECT_NEAR(z, 35, 1e-9) << f;
    } else if (t < t_move + ramp) {
      EXPECT_NEAR(z, 35 - 3 * (t - t_move) / ramp, 1e-9) << f;  // on its way
      EXPECT_GT(z, 32.01) << f;
      ++during;
    } else if (live.spheres[4 * static_cast<size_t>(f) + 3] > 0) {
      EXPECT_NEAR(z, 32, 1e-9) << f;
    }
  }
  EXPECT_GE(during, 2);  // frames every 0.01 s over a 0.03 s ramp
  expect_replays(session, dir.path(), "ramp");
}

// A ramp under way when the model becomes unstable ends at the frame the session goes back to, where
// it had brought the tool; the frames up to it are those shown (to float rounding) and replay.
TEST(LiveSession, ARampUnderWayWhenTheModelStopsEndsAtTheFrameBefore) {
  TempDir dir;
  ctsurg::sim::test::write_block_files(dir.path(), 16, 4, 4, 2.0);
  LiveSession session = session_of(dir.path(), live_bar_text());
  session.set_move_ramp_s(0.05);
  const int grab = session.begin_tool({&tool_type("grab"), 2.5, {}, {42, -15, 35}});
  session.advance_events(30);
  const double t_move = session.time();
  session.move_tool(grab, {42, -215, 35});
  // 200 mm over 0.05 s: the bar gives way after the frame at 0.01 s, mid-ramp.
  LiveAdvance r;
  Trajectory shown = session.trajectory();
  for (int k = 0; k < 2000 && !r.stopped; ++k) {
    r = session.advance_events(1);
    if (r.frames > 0 && !r.stopped) shown = session.trajectory();
  }
  ASSERT_TRUE(r.stopped);
  EXPECT_NE(session.stopped_message().find("unstable"), std::string::npos) << session.stopped_message();
  const double t_frame = session.time();
  ASSERT_GT(t_frame, t_move);
  ASSERT_LT(t_frame, t_move + 0.05);
  // The frames kept are those shown, to float rounding.
  const Trajectory kept = session.trajectory();
  ASSERT_EQ(kept.frame_count(), shown.frame_count());
  EXPECT_EQ(kept.time, shown.time);
  ASSERT_EQ(kept.vertices.size(), shown.vertices.size());
  for (size_t i = 0; i < kept.vertices.size(); ++i) ASSERT_NEAR(kept.vertices[i], shown.vertices[i], 1e-4) << i;
  // The grab's path ends at the frame, where the ramp had brought it (linearly from t_move).
  const Scenario saved = parse_scenario(session.scenario_text("x.h5"), dir.path() / "x.yaml", dir.path());
  const Keyframe& last = saved.tools.back().path.back();
  EXPECT_EQ(last.t, t_frame);
  EXPECT_NEAR(last.point.value[1], -15 - 200 * (t_frame - t_move) / 0.05, 1e-9);
  EXPECT_EQ(last.point.value[2], 35);
  // The grab still holds; the session goes on from there and replays.
  EXPECT_TRUE(session.tool_active(grab));
  session.resume();
  session.move_tool(grab, {42, -20, 35});
  ASSERT_FALSE(session.advance_events(300).stopped) << session.stopped_message();
  expect_replays(session, dir.path(), "ramp_cut");
}
