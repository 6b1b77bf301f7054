// Running a scenario (scenario.h): build the model from the named files, fix the fixed regions, step
// with Verlet at the chosen step while the tool timeline grabs, probes and cuts, move and cut the
// surface, watch stability, and collect the output frames as a Trajectory (core/trajectory_file.h).
//
// Per step, in order: the spring forces and the Verlet update (spring_mass_step.h); then, at the new
// time t, each active tool: grabbed particles set to the tool's centre + their offsets (captured at the
// first step at or after start_s, released at end_s), probe spheres push particles out, and a blade
// cuts every spring and surface triangle crossing the area it swept since the last step (its edge at
// t - dt and at t; a blade that does not move cuts nothing). A frame is recorded at t = 0 and at every
// multiple of frame_interval_s (the step's time nearest to it), and the stability guard checks each
// frame and every 1,000 steps; an unstable run stops with a RuntimeError naming the time, the place and a
// step to try, or, when the scenario allows max_step_halvings, restarts from the last frame with half
// the step. A trajectory never holds a non-finite value.
//
// Metrics per frame (units): kinetic_energy (nJ), elastic_energy (nJ), max_displacement (mm, over the
// particles), surface_max_displacement (mm), enclosed_volume (mm^3, of the surface; after a cut, of
// what remains, closed or not), springs_cut (count, cumulative), dt (s).
#pragma once

#include "ctsurg/core/trajectory_file.h"
#include "ctsurg/sim/scenario/scenario.h"

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace ctsurg::sim {

struct RunReport {
  int64_t particles = 0, fixed = 0;  // particles (spring models) or nodes (FEM); those held fixed
  int64_t springs = 0;               // spring models: springs present at the start
  int64_t elements = 0;              // FEM: tets
  double critical_dt_s = 0;  // the per-particle critical step (stability.h)
  double dt_s = 0;           // the step used at the end of the run
  int halvings = 0;          // step halvings after instability
  int64_t steps = 0;                 // time steps (FEM static: Newton iterations)
  int64_t springs_cut = 0;
  int64_t surface_triangles_removed = 0;
  double wall_s = 0;         // seconds in the time loop
  std::vector<std::string> notes;  // what the run decided (grab captures, auto step, ...), for the log
};

// Runs `scenario`; progress(fraction of the simulated time) is called now and then (may be empty).
// Throws InputError for a bad input file or a tool/region that selects nothing, RuntimeError when the
// run is unstable beyond the allowed halvings.
Trajectory run_scenario(const Scenario& scenario, RunReport* report = nullptr,
                        const std::function<void(double)>& progress = {});

}  // namespace ctsurg::sim
