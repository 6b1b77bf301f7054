// A scenario's tools over time: each tool's path resolved to the run's frame and its time window, and
// from them the tools' inputs to a simulation engine (base/simulation_engine.h) at any time.
//
// Paths. Keyframes given as LPS positions, as fractions of the tissue's rest bounding box, or as offsets
// from the first keyframe (scenario.h) become points of the run's local frame (LPS minus the engine's
// origin); the tool moves linearly between keyframes and stays at the first before it and the last
// after it. snap_to_tissue shifts the whole path so that its first point is on the nearest rest
// particle (lowest id on ties).
//
// Orientations. An instrument's keyframes may give its rotation (scenario.h); a key without one keeps
// the previous key's (the first: the identity); between keys the rotation is slerped (base/rigid_pose.h)
// on the same time fraction as the position. The instrument's mesh is read and its distance grid baked
// when the timeline is made (InputError naming the mesh file when it is not a closed mesh).
//
// Windows. A tool is active from start_s to end_s: start_s - 1e-12 <= t < end_s (the tolerance keeps a
// step that lands on start_s in floating point from missing it).
//
// Sutures. Their stitches' points become points of the local frame; a line of stitches (`along`) is
// spaced along its line, each stitch across it along `across` or, without one, along the line's
// direction x the tissue's outward direction at the line's middle (from the centroid of the rest
// particles within 15 mm of it to the middle). A suture's path is its first stitch's first point.
//
// Blades. A blade sweeps from where its last sweep ended once its centre has moved min_sweep_mm (the
// engine's blade_sweep_mm(): a quarter of the shortest spring, so no spring slips between two sweeps),
// or reaches a keyframe or its end: each sweep then lies on one straight segment of the path, a planar
// quad the engine cuts as two triangles. The sweep state is the timeline's own: sweep_state() is its
// checkpoint and restore_sweeps() takes it back.
//
// Growing while running (a live session, sim/live/live_session.h). add_tool() appends a grab, probe or
// cut whose keyframes are LPS positions; add_keyframe() appends a keyframe after its last one (or
// replaces the last one at the same time, before any step used it); set_end() closes its window. Each
// change must lie in the future of every inputs() call made so far (keyframe times and windows after
// the last t1): then the inputs from here on are those of a timeline that held the change from the
// start, blade sweeps included (a sweep never crosses a keyframe, and those before t1 are unchanged).
//
// Units: mm, s.
#pragma once

#include "ctsurg/sim/base/simulation_engine.h"
#include "ctsurg/sim/scenario/scenario.h"

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace ctsurg::sim {

class ToolTimeline {
 public:
  // tools: the scenario's; rest: the model's rest positions (#P x 3 mm, local frame: LPS minus
  // `origin`); note receives what was decided (path snaps; may be empty); where names the scenario in
  // messages (InputError(where, "tools[i].suture.along", ...) for a suture line off the tissue).
  ToolTimeline(const std::vector<ToolAction>& tools, const std::vector<double>& rest, const Vec3& origin,
               const std::function<void(const std::string&)>& note = {}, const std::string& where = "scenario");

  size_t size() const { return tools_.size(); }
  const ToolAction& tool(size_t i) const { return tools_[i].spec; }
  Vec3 position(size_t i, double t) const;   // mm, local frame
  Quaternion orientation(size_t i, double t) const;  // an instrument's rotation (others: the identity)
  // An instrument's shape (null for the other tools).
  const std::shared_ptr<const Instrument>& instrument(size_t i) const { return tools_[i].instrument; }
  // A suture's stitches as given (mm, local frame), in order: its stitches, then its line's.
  const std::vector<std::array<Vec3, 2>>& stitch_points(size_t i) const { return tools_[i].stitch_points; }
  bool active(size_t i, double t) const;
  // Whether no tool acts (starts, moves or holds) in (t0, t1].
  bool idle(double t0, double t1) const;

  // The tools as an engine takes them for the interval (t0, t1]: one ToolInput per tool, in the
  // scenario's order, with its window and centre at t1; blades with the sweeps since their last one
  // (min_sweep_mm: the engine's blade_sweep_mm()). Advances the blades' sweep state.
  void inputs(double t0, double t1, double min_sweep_mm, std::vector<ToolInput>& out);

  // Growing while running (see above). spec: kind grab, probe or cut, every keyframe a position_mm (LPS,
  // moved into the local frame by `origin`, as the constructor does), no snap_to_tissue; InputError(where,
  // spec.label, ...) otherwise. Returns the tool's index.
  size_t add_tool(const ToolAction& spec, const Vec3& origin, const std::string& where = "live session");
  // Tool i's keyframe at t (s) at `lps` (mm): after its last keyframe, or replacing the last one when t
  // is its time. The tool's spec (tool(i).path) records it too.
  void add_keyframe(size_t i, double t, const std::array<double, 3>& lps, const Vec3& origin);
  void set_end(size_t i, double end_s);  // tool i's window closes at end_s (s, after its start)
  // The blades' sweep state (per tool, the time its current sweep started), to restore_sweeps() on a
  // restart from that point: tools added since have not swept yet.
  using SweepState = std::vector<std::optional<double>>;
  SweepState sweep_state() const;
  void restore_sweeps(const SweepState& checkpoint);

 private:
  struct Path {
    std::vector<double> t;  // s, increasing
    std::vector<Vec3> p;    // mm
    std::vector<Quaternion> r;  // unit, one per key
    Vec3 at(double time) const;
    Quaternion rotation_at(double time) const;
  };
  struct Tool {
    ToolAction spec;  // a copy: the timeline does not depend on the scenario living on
    Path path;
    std::optional<double> cut_from;  // a blade: the time its current sweep started
    std::shared_ptr<const Instrument> instrument;
    std::vector<std::array<Vec3, 2>> stitch_points;  // suture: mm, local frame
    std::vector<std::string> stitch_fields;          // suture: each stitch's field, for messages
  };
  void sweeps(Tool& tool, double t0, double t1, double min_sweep_mm, std::vector<std::array<Vec3, 2>>& out) const;

  std::vector<Tool> tools_;
};

}  // namespace ctsurg::sim
