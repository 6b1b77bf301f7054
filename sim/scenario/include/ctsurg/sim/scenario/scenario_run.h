// Running a scenario (scenario.h): its model becomes a simulation engine (scenario_engine.h: spring
// grid, explicit springs or tetrahedral FEM, on the CPU or a CUDA device), its tools a timeline
// (tool_timeline.h), and one loop drives the engine to the end:
//
//   advance to the next event   one time step with the tools as they are at its end (several at once
//                               while no tool acts, for an engine that batches them), or, for a
//                               quasi-static engine, the equilibrium at the next output frame;
//   check stability             at every frame and every 1,000 steps (and at every step where the
//                               engine checks itself); an unstable run stops with a RuntimeError naming
//                               the time, the place and a step to try, or, when the scenario allows
//                               max_step_halvings and the engine can restart, goes back to the last
//                               frame with half the step;
//   record a frame              at t = 0 and at every multiple of frame_interval_s (the step's time
//                               nearest to it) (trajectory_recorder.h: surface, topology, tools,
//                               metrics). A trajectory never holds a non-finite value.
//
// The engines document what happens within a step (springs/spring_engine.h, fem/fem_engine.h).
#pragma once

#include "ctsurg/core/trajectory_file.h"
#include "ctsurg/sim/scenario/scenario.h"
#include "ctsurg/sim/scenario/scenario_engine.h"
#include "ctsurg/sim/scenario/tool_timeline.h"
#include "ctsurg/sim/scenario/trajectory_recorder.h"

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace ctsurg::sim {

struct RunReport {
  int64_t particles = 0, fixed = 0;  // particles (spring models) or nodes (FEM); those held fixed (every axis)
  int64_t partly_fixed = 0;          // those held in some axes only (the tools move their free axes)
  int64_t springs = 0;               // spring models: springs present at the start
  int64_t elements = 0;              // FEM: tets
  double critical_dt_s = 0;  // the critical step (springs/stability.h, fem/fem_explicit_dynamics.h)
  double dt_s = 0;           // the step used at the end of the run
  int halvings = 0;          // step halvings after instability
  int64_t steps = 0;                 // time steps (quasi-static FEM: Newton iterations)
  int64_t springs_cut = 0;
  int64_t surface_triangles_removed = 0;
  double wall_s = 0;         // seconds in the time loop
  double setup_s = 0;        // seconds building the engine (files read, model, factorisations): run_scenario(Scenario) only
  std::vector<double> frame_wall_s;  // per recorded frame: seconds in the loop up to it (frame 0: 0)
  std::vector<std::string> notes;  // what the run decided (grab captures, auto step, ...), for the log
};

// A limit on how long a run may take. After `sample_s` seconds of running, the run's total time is
// estimated from its speed so far (wall time per simulated second); when the estimate exceeds
// `max_wall_s`, the run stops with an InputError naming time.duration_s, the estimate and the limit
// (ctsurg-sim --force lifts it). max_wall_s = 0: no limit.
struct RunBudget {
  double max_wall_s = 0;
  double sample_s = 1.0;
};

// The loop, one event at a time: run_scenario drives it to the scenario's last frame; a live session
// (sim/live/live_session.h) drives it for as long as its user works, adding tools and keyframes to
// timeline() between events (they act from next_time() on). Both therefore compute the same tool
// inputs, batch the same steps, check stability at the same steps and record the same frames, so a
// live session saved as a scenario replays through run_scenario to the same trajectory.
class ScenarioLoop {
 public:
  // What one advance() did.
  struct Event {
    bool recorded = false;   // a frame was recorded
    bool restarted = false;  // unstable: restarted from the last frame with half the step (restart says why)
    StabilityReport restart;
    // Unstable beyond the allowed halvings (stable == false): the loop cannot go on;
    // unstable_message() says why, with a step to try.
    StabilityReport unstable;
  };
  // built: the engine (make_scenario_engine); frames: how many frames the recorder reserves (the
  // run's); note receives what the loop and the timeline decide (may be empty).
  ScenarioLoop(const Scenario& scenario, ScenarioEngine built, int64_t frames,
               const std::function<void(const std::string&)>& note = {});
  ScenarioLoop(const ScenarioLoop&) = delete;
  ScenarioLoop& operator=(const ScenarioLoop&) = delete;

  // Advances to the next event (scenario_run.h's loop body): one step with the tools as they are at its
  // end (several while no tool acts, for an engine that batches them), or a quasi-static engine's
  // equilibrium at the next frame; checks stability; restarts with half the step when allowed;
  // records the frame when one is due.
  Event advance();
  // The time (s) the next advance() ends its first step at (quasi-static: the next frame's time): a
  // tool added or moved now acts from then.
  double next_time() const;
  int64_t next_frame() const { return next_frame_; }  // index of the next frame to record
  int halvings() const { return halvings_; }
  // The message for an Event's unstable report: the guard's, and what to change.
  std::string unstable_message(const StabilityReport& unstable) const;

  SimulationEngine& engine() { return *engine_; }
  const SimulationEngine& engine() const { return *engine_; }
  ToolTimeline& timeline() { return timeline_; }
  const ToolTimeline& timeline() const { return timeline_; }
  TrajectoryRecorder& recorder() { return recorder_; }
  const TrajectoryRecorder& recorder() const { return recorder_; }

 private:
  const Scenario& s_;
  std::unique_ptr<SimulationEngine> engine_;
  std::function<void(const std::string&)> note_;
  ToolTimeline timeline_;
  TrajectoryRecorder recorder_;
  bool restartable_ = false;
  ToolTimeline::SweepState checkpoint_sweeps_;  // the blades' sweep state at the last frame
  size_t checkpoint_frames_ = 0;
  int halvings_ = 0;
  int64_t next_frame_ = 1;
  std::vector<ToolInput> tools_;
};

// Runs `scenario`; progress(fraction of the simulated time) is called now and then (may be empty).
// Throws InputError for a bad input file or a tool/region that selects nothing, or a run estimated
// to take longer than `budget` allows; RuntimeError when the run is unstable beyond the allowed
// halvings.
Trajectory run_scenario(const Scenario& scenario, RunReport* report = nullptr,
                        const std::function<void(double)>& progress = {}, const RunBudget& budget = {});
// The same loop over an engine the caller made (make_scenario_engine, or any SimulationEngine that takes
// this scenario's tools): the seam for models beyond the scenario's kinds. The scenario gives the tools,
// the time and the output; of its model section only the label (scenario_model.h) and the surface file
// (hashed into the trajectory when the engine has a surface) are used. report->notes holds what the
// loop decided.
Trajectory run_scenario(const Scenario& scenario, ScenarioEngine engine, RunReport* report = nullptr,
                        const std::function<void(double)>& progress = {}, const RunBudget& budget = {});

}  // namespace ctsurg::sim
