#include "ctsurg/sim/scenario/scenario_run.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/scenario/scenario_engine.h"
#include "ctsurg/sim/scenario/tool_timeline.h"
#include "ctsurg/sim/scenario/trajectory_recorder.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace ctsurg::sim {
namespace {

constexpr int64_t kGuardInterval = 1000;  // steps between stability checks (besides every frame)

std::string duration_text(double seconds) {
  char text[64];
  if (seconds < 120) {
    std::snprintf(text, sizeof text, "%.0f s", seconds);
  } else if (seconds < 7200) {
    std::snprintf(text, sizeof text, "%.0f min", seconds / 60);
  } else if (seconds < 3 * 86400) {
    std::snprintf(text, sizeof text, "%.1f h", seconds / 3600);
  } else {
    std::snprintf(text, sizeof text, "%.3g days", seconds / 86400);
  }
  return text;
}

// After budget.sample_s of running: the estimate of the whole run from its speed so far (true once
// it was made; InputError when it exceeds the budget).
bool check_budget(const Scenario& s, const SimulationEngine& engine, const RunBudget& budget,
                  std::chrono::steady_clock::duration elapsed) {
  const double wall = std::chrono::duration<double>(elapsed).count();
  if (wall < budget.sample_s) return false;
  const double simulated = engine.time();
  const double estimate = simulated > 0 ? wall * s.duration_s / simulated : std::numeric_limits<double>::infinity();
  if (estimate <= budget.max_wall_s) return true;
  std::string steps;
  if (!engine.quasi_static() && engine.dt() > 0) {
    char text[96];
    std::snprintf(text, sizeof text, " (%.3g steps of %.3g s)", s.duration_s / engine.dt(), engine.dt());
    steps = text;
  }
  throw InputError(s.file.string(), "time.duration_s",
                   "this run would take about " + duration_text(estimate) + " on this machine" + steps + ", judged by its first " +
                       duration_text(wall) + "; the limit is " + duration_text(budget.max_wall_s) +
                       ": shorten duration_s, coarsen the model or the step, or run it anyway with --force");
}

// The loop (scenario_run.h); report already holds the notes of the engine's construction.
Trajectory run(const Scenario& s, ScenarioEngine built, RunReport& report, const std::function<void(double)>& progress,
               const RunBudget& budget) {
  if (!built.engine) throw RuntimeError(s.file.string() + ": no engine to run");
  const std::string sfile = s.file.string();
  const auto note = [&](const std::string& text) { report.notes.push_back(text); };
  SimulationEngine& engine = *built.engine;
  ToolTimeline timeline(s.tools, engine.rest_positions(), engine.origin(), note, sfile);
  const int64_t frame_count = static_cast<int64_t>(std::floor(s.duration_s / s.frame_interval_s + 1e-9)) + 1;
  TrajectoryRecorder recorder(s, engine, timeline, std::move(built.surface_lps_vertices), frame_count);
  const EngineCounts counts = engine.counts();
  report.particles = counts.nodes;
  report.fixed = counts.fixed;
  report.springs = counts.springs;
  report.elements = counts.elements;
  report.critical_dt_s = counts.critical_dt_s;

  const auto start = std::chrono::steady_clock::now();
  engine.sync();
  recorder.record(engine, timeline, 0.0);
  report.frame_wall_s.assign(1, 0.0);
  // The last frame, for restarts with half the step; kept only when the run may restart.
  const bool restartable = s.max_step_halvings > 0 && engine.can_restart();
  ToolTimeline checkpoint_timeline = timeline;
  size_t checkpoint_frames = recorder.frames();
  if (restartable) engine.save_checkpoint();
  int halvings = 0;
  double last_progress = -1;
  std::vector<ToolInput> tools;
  int64_t next_frame = 1;
  bool estimated = budget.max_wall_s <= 0;
  int64_t iterations = 0;
  while (next_frame < frame_count) {
    if (!estimated && ++iterations % 16 == 0) {
      estimated = check_budget(s, engine, budget, std::chrono::steady_clock::now() - start);
    }
    // Advance to the next event: one step (several while no tool acts, for an engine that batches them),
    // or a quasi-static engine's equilibrium at the next frame.
    const double t_frame = static_cast<double>(next_frame) * s.frame_interval_s;
    StabilityReport check;
    if (engine.quasi_static()) {
      timeline.inputs(engine.time(), t_frame, engine.blade_sweep_mm(), tools);
      engine.equilibrium(tools, t_frame);
    } else {
      const double t = engine.time(), dt = engine.dt(), t_next = t + dt;
      timeline.inputs(t, t_next, engine.blade_sweep_mm(), tools);
      const int steps = engine.batches_steps() && timeline.idle(t_next, t_frame)
                            ? static_cast<int>(std::clamp(std::floor((t_frame - t) / dt + 0.5), 1.0, 1e6))
                            : 1;
      check = engine.step(tools, steps);
    }
    const bool frame_due = engine.quasi_static() || engine.time() >= t_frame - 0.5 * engine.dt();
    if (check.stable && (frame_due || engine.steps() % kGuardInterval == 0)) check = engine.check_stability();
    if (!check.stable) {
      if (!restartable || halvings >= s.max_step_halvings) {
        std::string hint;
        if (engine.can_restart()) {
          hint = s.max_step_halvings > 0 ? " (after " + std::to_string(halvings) + " step halvings)"
                                         : " Set time.dt_s lower, or allow time.max_step_halvings.";
        }
        throw RuntimeError(sfile + ": the run became unstable: " + check.message + hint);
      }
      // Restart from the last frame with half the step.
      engine.restart_halved();
      timeline = checkpoint_timeline;
      recorder.truncate(checkpoint_frames);
      report.frame_wall_s.resize(checkpoint_frames);
      next_frame = static_cast<int64_t>(checkpoint_frames);
      ++halvings;
      note("unstable at t = " + std::to_string(check.time) + " s: restarted from t = " + std::to_string(engine.time()) +
           " s with dt = " + std::to_string(engine.dt()) + " s (" + check.message + ")");
      continue;
    }
    if (frame_due) {
      engine.sync();
      recorder.record(engine, timeline, engine.time());
      report.frame_wall_s.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      ++next_frame;
      if (restartable) {
        engine.save_checkpoint();
        checkpoint_timeline = timeline;
        checkpoint_frames = recorder.frames();
      }
      const double fraction = engine.time() / s.duration_s;
      if (progress && fraction - last_progress >= 0.01) {
        progress(fraction);
        last_progress = fraction;
      }
    }
  }
  const EngineMetrics end = engine.metrics();
  report.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  report.dt_s = engine.dt();
  report.halvings = halvings;
  report.steps = engine.steps();
  report.springs_cut = end.springs_cut;
  report.surface_triangles_removed = end.triangles_removed;
  if (progress) progress(1.0);
  return recorder.finish(engine.dt());
}

}  // namespace

Trajectory run_scenario(const Scenario& s, RunReport* report_out, const std::function<void(double)>& progress,
                        const RunBudget& budget) {
  RunReport report;
  const auto t0 = std::chrono::steady_clock::now();
  ScenarioEngine engine = make_scenario_engine(s, [&](const std::string& text) { report.notes.push_back(text); });
  report.setup_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  Trajectory traj = run(s, std::move(engine), report, progress, budget);
  if (report_out) *report_out = std::move(report);
  return traj;
}

Trajectory run_scenario(const Scenario& s, ScenarioEngine engine, RunReport* report_out,
                        const std::function<void(double)>& progress, const RunBudget& budget) {
  RunReport report;
  Trajectory traj = run(s, std::move(engine), report, progress, budget);
  if (report_out) *report_out = std::move(report);
  return traj;
}

}  // namespace ctsurg::sim
