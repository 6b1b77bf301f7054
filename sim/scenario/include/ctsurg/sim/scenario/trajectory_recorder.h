// Collects a run's output frames into a Trajectory (core/trajectory_file.h): per frame the time, the
// surface's vertices (or the nodes' when the scenario has no surface) and its topology when a cut
// changed it (and how many of its last triangles close the cut's holes), optionally every node's position, the tools (spheres: centre and radius, 0 when not
// acting; blades: the edge's ends and whether it is active; instruments: their meshes once and their
// poses per frame; stitches: their two points and whether they are placed; the sphere tools' loads on
// the tissue when the engine measures them: SimulationEngine::tool_load), the engine's local region
// per surface vertex when it has one (SimulationEngine::surface_vertex_region: frames before it had one
// read 0), and the metrics:
//
//   kinetic_energy (nJ), elastic_energy (nJ), max_displacement (mm, over the nodes),
//   surface_max_displacement (mm, over the surface's vertices; the nodes' when there is none),
//   enclosed_volume (mm^3) and surface_area (mm^2) of the surface (0 without one), springs_cut
//   (cumulative), dt (s), then the engine's own (extra_metrics(): a static FEM's iterations).
//
// Positions go out in LPS: the engine's local frame plus its origin, added in double before rounding
// to the file's float. truncate() drops the frames after a checkpoint when a run restarts.
//
// A tool added to the timeline while running (a live session's, ToolTimeline::add_tool) is added here
// by add_tool(): its entries for the frames already recorded are those record() writes for a tool that
// has not started (its first keyframe's position, not acting), so the trajectory is the one a run that
// held the tool from the start records.
#pragma once

#include "ctsurg/core/trajectory_file.h"
#include "ctsurg/sim/base/simulation_engine.h"
#include "ctsurg/sim/scenario/scenario.h"
#include "ctsurg/sim/scenario/tool_timeline.h"

#include <cstdint>
#include <string_view>
#include <vector>

namespace ctsurg::sim {

class TrajectoryRecorder {
 public:
  // scenario: its name, surface file and output options; engine: the model (nodes, origin, surface);
  // surface_lps_vertices: the surface file's vertices (#V x 3 LPS mm, the trajectory's rest surface),
  // empty without a surface; frames: how many frames the run records. Throws InputError(scenario file,
  // "output.frame_interval_s", ...) when the frames would not fit in memory.
  TrajectoryRecorder(const Scenario& scenario, const SimulationEngine& engine, const ToolTimeline& timeline,
                     std::vector<float> surface_lps_vertices, int64_t frames);

  // Records the engine's state (after its sync()) as the frame at time t (s).
  void record(SimulationEngine& engine, const ToolTimeline& timeline, double t);
  size_t frames() const { return traj_.time.size(); }
  // The named metric's value at the last recorded frame; NaN without such a metric or a frame.
  double last_metric(std::string_view name) const;
  void truncate(size_t frames);
  // Tool i of the timeline, added since the last record() (a grab, probe or cut that starts after the
  // frames recorded so far), once its first keyframe is final; tools are added in the timeline's order.
  void add_tool(const ToolTimeline& timeline, size_t i);
  // The trajectory so far (a copy; the recorder goes on); dt: the run's step now.
  Trajectory snapshot(double dt) const;
  // The trajectory (the recorder is spent); dt: the run's final step.
  Trajectory finish(double dt);

 private:
  Trajectory traj_;
  Vec3 origin_;
  bool write_particles_;
  void finish_into(Trajectory& traj, double dt) const;  // dt, metrics, closing triangles
  size_t tools_ = 0;                // the timeline's tools recorded
  size_t blades_ = 0;               // cut tools
  bool removal_ = false;            // a tool removes tissue: the removed_volume metric (mm^3) is recorded
  size_t stitches_ = 0;             // the sutures' stitches
  std::vector<int64_t> closing_;    // per topology: its last triangles closing cut holes
  std::vector<TrajectoryMetric> metrics_;
  std::vector<double> loads_;       // F x S x 7: each sphere tool's load (SimulationEngine::tool_load)
  bool any_load_ = false;           // some load was measured: the trajectory carries them
  std::vector<float> vertices_;    // scratch: the frame's vertices, local frame
  std::vector<uint8_t> region_;    // scratch: the frame's local-region flags
  std::vector<double> positions_;  // scratch: the nodes' positions, local frame
};

}  // namespace ctsurg::sim
