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

std::unique_ptr<SimulationEngine> engine_of(std::unique_ptr<SimulationEngine> engine, const Scenario& s) {
  if (!engine) throw RuntimeError(s.file.string() + ": no engine to run");
  return engine;
}

// The loop (scenario_run.h); report already holds the notes of the engine's construction.
Trajectory run(const Scenario& s, ScenarioEngine built, RunReport& report, const std::function<void(double)>& progress,
               const RunBudget& budget) {
  const int64_t frame_count = static_cast<int64_t>(std::floor(s.duration_s / s.frame_interval_s + 1e-9)) + 1;
  ScenarioLoop loop(s, std::move(built), frame_count, [&](const std::string& text) { report.notes.push_back(text); });
  const auto start = std::chrono::steady_clock::now();
  SimulationEngine& engine = loop.engine();
  const EngineCounts counts = engine.counts();
  report.particles = counts.nodes;
  report.fixed = counts.fixed;
  report.partly_fixed = counts.partly_fixed;
  report.springs = counts.springs;
  report.elements = counts.elements;
  report.critical_dt_s = counts.critical_dt_s;
  report.frame_wall_s.assign(1, 0.0);
  double last_progress = -1;
  bool estimated = budget.max_wall_s <= 0;
  int64_t iterations = 0;
  while (loop.next_frame() < frame_count) {
    if (!estimated && ++iterations % 16 == 0) {
      estimated = check_budget(s, engine, budget, std::chrono::steady_clock::now() - start);
    }
    const ScenarioLoop::Event event = loop.advance();
    if (!event.unstable.stable) {
      throw RuntimeError(s.file.string() + ": the run became unstable: " + loop.unstable_message(event.unstable));
    }
    if (event.restarted) report.frame_wall_s.resize(loop.recorder().frames());
    if (event.recorded) {
      report.frame_wall_s.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
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
  report.halvings = loop.halvings();
  report.steps = engine.steps();
  report.springs_cut = end.springs_cut;
  report.surface_triangles_removed = end.triangles_removed;
  if (progress) progress(1.0);
  return loop.recorder().finish(engine.dt());
}

}  // namespace

ScenarioLoop::ScenarioLoop(const Scenario& s, ScenarioEngine built, int64_t frames,
                           const std::function<void(const std::string&)>& note)
    : s_(s),
      engine_(engine_of(std::move(built.engine), s)),
      note_(note),
      timeline_(s.tools, engine_->rest_positions(), engine_->origin(), note, s.file.string()),
      recorder_(s, *engine_, timeline_, std::move(built.surface_lps_vertices), frames),
      checkpoint_sweeps_(timeline_.sweep_state()) {
  engine_->sync();
  recorder_.record(*engine_, timeline_, 0.0);
  // The last frame, for restarts with half the step; kept only when the run may restart.
  restartable_ = s.max_step_halvings > 0 && engine_->can_restart();
  checkpoint_frames_ = recorder_.frames();
  if (restartable_) engine_->save_checkpoint();
}

double ScenarioLoop::next_time() const {
  const SimulationEngine& engine = *engine_;
  return engine.quasi_static() ? static_cast<double>(next_frame_) * s_.frame_interval_s : engine.time() + engine.dt();
}

std::string ScenarioLoop::unstable_message(const StabilityReport& unstable) const {
  std::string hint;
  if (engine_->can_restart()) {
    hint = s_.max_step_halvings > 0 ? " (after " + std::to_string(halvings_) + " step halvings)"
                                    : " Set time.dt_s lower, or allow time.max_step_halvings.";
  }
  return unstable.message + hint;
}

ScenarioLoop::Event ScenarioLoop::advance() {
  SimulationEngine& engine = *engine_;
  Event event;
  // Advance to the next event: one step (several while no tool acts, for an engine that batches them),
  // or a quasi-static engine's equilibrium at the next frame.
  const double t_frame = static_cast<double>(next_frame_) * s_.frame_interval_s;
  StabilityReport check;
  if (engine.quasi_static()) {
    timeline_.inputs(engine.time(), t_frame, engine.blade_sweep_mm(), tools_);
    engine.equilibrium(tools_, t_frame);
  } else {
    const double t = engine.time(), dt = engine.dt(), t_next = t + dt;
    timeline_.inputs(t, t_next, engine.blade_sweep_mm(), tools_);
    const int steps = engine.batches_steps() && timeline_.idle(t_next, t_frame)
                          ? static_cast<int>(std::clamp(std::floor((t_frame - t) / dt + 0.5), 1.0, 1e6))
                          : 1;
    check = engine.step(tools_, steps);
  }
  const bool frame_due = engine.quasi_static() || engine.time() >= t_frame - 0.5 * engine.dt();
  if (check.stable && (frame_due || engine.steps() % kGuardInterval == 0)) check = engine.check_stability();
  if (!check.stable) {
    if (!restartable_ || halvings_ >= s_.max_step_halvings) {
      event.unstable = check;
      return event;
    }
    // Restart from the last frame with half the step. The timeline goes back to its blades' sweep
    // state then; its tools and keyframes stay (a live session's, added since, are in its future).
    engine.restart_halved();
    timeline_.restore_sweeps(checkpoint_sweeps_);
    recorder_.truncate(checkpoint_frames_);
    next_frame_ = static_cast<int64_t>(checkpoint_frames_);
    ++halvings_;
    if (note_) {
      note_("unstable at t = " + std::to_string(check.time) + " s: restarted from t = " + std::to_string(engine.time()) +
            " s with dt = " + std::to_string(engine.dt()) + " s (" + check.message + ")");
    }
    event.restarted = true;
    event.restart = check;
    return event;
  }
  if (frame_due) {
    engine.sync();
    recorder_.record(engine, timeline_, engine.time());
    ++next_frame_;
    if (restartable_) {
      engine.save_checkpoint();
      checkpoint_sweeps_ = timeline_.sweep_state();
      checkpoint_frames_ = recorder_.frames();
    }
    event.recorded = true;
  }
  return event;
}

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
