#include "ctsurg/sim/live/live_session.h"

#include "live_scenario_text.h"

#include "ctsurg/core/atomic_output.h"
#include "ctsurg/core/error.h"
#include "ctsurg/core/provenance.h"
#include "ctsurg/core/version.h"
#include "ctsurg/sim/scenario/scenario_engine.h"
#include "ctsurg/sim/scenario/scenario_model.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>

namespace ctsurg::sim {

namespace {

constexpr const char* kSessionWhere = "live session";

bool finite3(const std::array<double, 3>& v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

double length(const std::array<double, 3>& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

}  // namespace

struct LiveSession::Pending {
  enum class Kind { begin, move, end } kind = Kind::begin;
  int id = 0;
  LiveToolSpec spec;  // begin: the tool; move: position_mm
};

LiveSession::LiveSession(Scenario scenario, std::string text, std::function<void(const std::string&)> note)
    : scenario_(std::move(scenario)), text_(std::move(text)), note_(std::move(note)) {
  build({}, 1);
}

LiveSession::~LiveSession() = default;

void LiveSession::build(const std::vector<ToolAction>& user_tools, int64_t replay_frames) {
  loop_.reset();  // it refers to loop_scenario_
  loop_scenario_ = scenario_;
  loop_scenario_.tools.insert(loop_scenario_.tools.end(), user_tools.begin(), user_tools.end());
  ScenarioEngine built = make_scenario_engine(loop_scenario_, note_);
  loop_ = std::make_unique<ScenarioLoop>(loop_scenario_, std::move(built), 1, note_);
  while (static_cast<int64_t>(loop_->recorder().frames()) < replay_frames) {
    const ScenarioLoop::Event event = loop_->advance();
    if (!event.unstable.stable) {
      throw RuntimeError(std::string(kSessionWhere) + ": replaying the recording became unstable: " +
                         loop_->unstable_message(event.unstable));
    }
  }
  last_frame_time_ = loop_->engine().time();
  last_triangles_ = loop_->engine().triangles();
  ++topology_version_;
}

int LiveSession::begin_tool(const LiveToolSpec& spec) {
  if (spec.kind == nullptr || !spec.kind->live) {
    throw InputError(kSessionWhere, "tool", std::string(spec.kind ? spec.kind->name : "no tool") + " is not a live tool (" +
                                                live_tool_names() + ")");
  }
  if (!finite3(spec.position_mm)) throw InputError(kSessionWhere, "position_mm", "must be three finite numbers");
  if (spec.kind->record == ToolRecord::blade) {
    const double l = length(spec.blade_edge_mm);
    if (!finite3(spec.blade_edge_mm) || !(l > 0) || l > kMaxLiveBladeMm) {
      throw InputError(kSessionWhere, "blade_edge_mm", "the blade's length must be in (0, " + exact_number(kMaxLiveBladeMm) + "] mm");
    }
  } else if (!(spec.radius_mm > 0) || !(spec.radius_mm <= kMaxLiveToolRadiusMm)) {
    throw InputError(kSessionWhere, "radius_mm", "must be in (0, " + exact_number(kMaxLiveToolRadiusMm) + "] mm");
  }
  const int id = static_cast<int>(ended_.size());
  ended_.push_back(false);
  pending_.push_back({Pending::Kind::begin, id, spec});
  return id;
}

void LiveSession::move_tool(int id, const std::array<double, 3>& position_mm) {
  if (!tool_active(id)) throw InputError(kSessionWhere, "id", std::to_string(id) + " is not a tool in use (begun and not ended)");
  if (!finite3(position_mm)) throw InputError(kSessionWhere, "position_mm", "must be three finite numbers");
  LiveToolSpec spec;
  spec.position_mm = position_mm;
  pending_.push_back({Pending::Kind::move, id, spec});
}

void LiveSession::end_tool(int id) {
  if (!tool_active(id)) throw InputError(kSessionWhere, "id", std::to_string(id) + " is not a tool in use (begun and not ended)");
  ended_[static_cast<size_t>(id)] = true;
  pending_.push_back({Pending::Kind::end, id, {}});
}

void LiveSession::set_move_ramp_s(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) {
    throw InputError(kSessionWhere, "move_ramp_s", "must be a finite number of seconds >= 0, not " + exact_number(seconds));
  }
  move_ramp_s_ = seconds;
}

bool LiveSession::tool_active(int id) const { return id >= 0 && static_cast<size_t>(id) < ended_.size() && !ended_[static_cast<size_t>(id)]; }

void LiveSession::resume() {
  paused_ = false;
  stopped_message_.clear();
}

void LiveSession::reset() {
  pending_.clear();
  ended_.clear();
  restart_message_.clear();
  stopped_message_.clear();
  build({}, 1);
}

double LiveSession::solver_error_mm() const { return loop_->recorder().last_metric("solver_error_mm"); }

std::vector<LiveToolLoad> LiveSession::tool_loads() const {
  std::vector<LiveToolLoad> loads;
  const SimulationEngine& e = loop_->engine();
  const size_t base = scenario_.tools.size();
  for (size_t i = base; i < loop_->timeline().size(); ++i) {
    std::array<double, 6> l{};
    if (!e.tool_load(i, l)) continue;
    loads.push_back({static_cast<int>(i - base), {l[0], l[1], l[2]}, {l[3], l[4], l[5]}});
  }
  return loads;
}

// The queued events at the boundary t = engine time, whose next event ends at t1 (live_session.h).
// Events wait while the timeline holds user keyframes or windows beyond t (after a restart with half
// the step the loop replays from its last frame: the recording's future is already written).
void LiveSession::apply_pending() {
  if (pending_.empty()) return;
  ToolTimeline& timeline = loop_->timeline();
  const Vec3& origin = loop_->engine().origin();
  const double t = loop_->engine().time(), t1 = loop_->next_time();
  const size_t base = scenario_.tools.size();
  for (size_t i = base; i < timeline.size(); ++i) {
    const ToolAction& tool = timeline.tool(i);
    if (tool.path.back().t > t || (std::isfinite(tool.end_s) && tool.end_s > t)) return;
  }
  std::vector<Pending> waiting;
  std::vector<size_t> begun;
  for (const Pending& p : pending_) {
    const size_t i = base + static_cast<size_t>(p.id);
    switch (p.kind) {
      case Pending::Kind::begin: {
        ToolAction tool;
        tool.type = p.spec.kind;
        tool.label = "tools[" + std::to_string(i) + "] (" + p.spec.kind->name + ")";
        tool.start_s = t1;
        tool.end_s = std::numeric_limits<double>::infinity();
        const bool blade = p.spec.kind->record == ToolRecord::blade;
        tool.radius_mm = blade ? 0 : p.spec.radius_mm;
        if (blade) tool.blade_edge_mm = p.spec.blade_edge_mm;
        Keyframe k;
        k.t = t1;
        k.point = {PointSpec::Kind::position_mm, p.spec.position_mm};
        tool.path.push_back(k);
        begun.push_back(timeline.add_tool(tool, origin, kSessionWhere));
        break;
      }
      case Pending::Kind::move: {
        if (i >= timeline.size()) {  // its begin waits
          waiting.push_back(p);
          break;
        }
        const Keyframe last = timeline.tool(i).path.back();
        if (last.t < t) timeline.add_keyframe(i, t, last.point.value, origin);
        timeline.add_keyframe(i, std::max(t1, t + move_ramp_s_), p.spec.position_mm, origin);
        break;
      }
      case Pending::Kind::end:
        // A tool begun at this boundary acts for one event before it ends.
        if (i >= timeline.size() || timeline.tool(i).start_s >= t1) {
          waiting.push_back(p);
        } else {
          timeline.set_end(i, t1);
        }
        break;
    }
  }
  // Into the recording once the boundary's moves have set their first keyframe.
  for (const size_t i : begun) loop_->recorder().add_tool(timeline, i);
  pending_ = std::move(waiting);
}

void LiveSession::track_topology() {
  const std::vector<uint32_t>& now = loop_->engine().triangles();
  if (now != last_triangles_) {
    last_triangles_ = now;
    ++topology_version_;
  }
}

// Back to the last recorded frame (live_session.h, "Stability"): the user's tools truncated to it, the
// engine rebuilt and the recording replayed up to it; paused with the reason kept.
void LiveSession::go_back(const std::string& why) {
  const ToolTimeline& timeline = loop_->timeline();
  const double t_frame = last_frame_time_;
  const int64_t frames = static_cast<int64_t>(loop_->recorder().frames());
  std::vector<ToolAction> tools;
  std::vector<bool> ended;
  for (size_t i = scenario_.tools.size(); i < timeline.size(); ++i) {
    ToolAction tool = timeline.tool(i);
    if (tool.start_s > t_frame) break;  // begun after the frame: later tools too
    std::optional<Keyframe> after;  // the first keyframe past the frame
    while (tool.path.size() > 1 && tool.path.back().t > t_frame) {
      after = tool.path.back();
      tool.path.pop_back();
    }
    // A ramp under way at the frame ends there, where it had brought the tool.
    if (after && tool.path.back().t < t_frame && after->point.value != tool.path.back().point.value) {
      const Vec3 local = timeline.position(i, t_frame);
      const Vec3& o = loop_->engine().origin();
      Keyframe cut = *after;
      cut.t = t_frame;
      cut.point.value = {local[0] + o[0], local[1] + o[1], local[2] + o[2]};
      tool.path.push_back(cut);
    }
    if (tool.end_s > t_frame) tool.end_s = std::numeric_limits<double>::infinity();
    ended.push_back(std::isfinite(tool.end_s));
    tools.push_back(std::move(tool));
  }
  build(tools, frames);
  ended_ = std::move(ended);
  pending_.clear();
  paused_ = true;
  stopped_message_ = why;
  if (note_) note_(std::string(kSessionWhere) + ": back to t = " + std::to_string(t_frame) + " s: " + why);
}

LiveAdvance LiveSession::advance_events(int64_t n) {
  LiveAdvance r;
  const auto start = std::chrono::steady_clock::now();
  const double t0 = time();
  for (int64_t k = 0; k < n && !paused_; ++k) {
    apply_pending();
    ScenarioLoop::Event event;
    try {
      event = loop_->advance();
    } catch (const InputError& e) {
      go_back(e.what());
      r.stopped = true;
      break;
    } catch (const RuntimeError& e) {
      go_back(e.what());
      r.stopped = true;
      break;
    }
    ++r.events;
    if (!event.unstable.stable) {
      go_back("the run became unstable: " + loop_->unstable_message(event.unstable));
      r.stopped = true;
      break;
    }
    if (event.restarted) {
      restart_message_ = event.restart.message;
      r.restarted = true;
    }
    if (event.recorded) {
      ++r.frames;
      last_frame_time_ = loop_->engine().time();
    }
  }
  track_topology();
  r.sim_s = time() - t0;
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

LiveAdvance LiveSession::advance(double wall_seconds, double realtime_factor) {
  LiveAdvance r;
  if (paused_ || !(wall_seconds > 0) || !(realtime_factor > 0)) return r;
  const auto start = std::chrono::steady_clock::now();
  const double t0 = time(), goal = t0 + wall_seconds * realtime_factor;
  while (time() < goal && !paused_) {
    const LiveAdvance one = advance_events(1);
    r.events += one.events;
    r.frames += one.frames;
    r.restarted |= one.restarted;
    r.stopped |= one.stopped;
    if (one.stopped) break;
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() >= wall_seconds) break;
  }
  r.sim_s = time() - t0;
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

double LiveSession::time() const { return loop_->engine().time(); }
int64_t LiveSession::steps() const { return loop_->engine().steps(); }
double LiveSession::dt() const { return loop_->engine().dt(); }
int LiveSession::halvings() const { return loop_->halvings(); }
int64_t LiveSession::frames() const { return static_cast<int64_t>(loop_->recorder().frames()); }
const SimulationEngine& LiveSession::engine() const { return loop_->engine(); }

void LiveSession::surface(std::vector<float>& lps) {
  SimulationEngine& engine = loop_->engine();
  engine.sync();
  std::vector<float> local;
  engine.surface_vertices(local);
  const Vec3& o = engine.origin();
  lps.resize(local.size());
  for (size_t i = 0; i < local.size(); ++i) lps[i] = static_cast<float>(local[i] + o[i % 3]);
}

const std::vector<uint32_t>& LiveSession::triangles() const { return loop_->engine().triangles(); }

std::array<double, 6> LiveSession::rest_bounds() const {
  const std::vector<double>& rest = loop_->engine().rest_positions();
  const Vec3& o = loop_->engine().origin();
  std::array<double, 6> b{1e300, 1e300, 1e300, -1e300, -1e300, -1e300};
  for (size_t i = 0; i + 2 < rest.size(); i += 3) {
    for (size_t c = 0; c < 3; ++c) {
      b[c] = std::min(b[c], rest[i + c] + o[c]);
      b[3 + c] = std::max(b[3 + c], rest[i + c] + o[c]);
    }
  }
  return b;
}

// The user's tools that act up to the last frame (those begun after it are left out: they acted on
// nothing recorded), as the timeline holds them.
std::vector<ToolAction> LiveSession::recorded_tools() const {
  const ToolTimeline& timeline = loop_->timeline();
  std::vector<ToolAction> tools;
  for (size_t i = scenario_.tools.size(); i < timeline.size(); ++i) {
    if (timeline.tool(i).start_s > last_frame_time_) break;
    tools.push_back(timeline.tool(i));
  }
  return tools;
}

// The saved run's duration: its frames are the ones recorded (floor(duration / interval) = the last
// frame's index), and every tool kept starts before it.
double LiveSession::save_duration() const {
  const int64_t last = frames() - 1;
  if (last < 1) throw InputError(kSessionWhere, "frames", "nothing recorded after the rest frame yet: run the session longer");
  const double fi = scenario_.frame_interval_s;
  double latest_start = 0;
  for (const ToolAction& tool : scenario_.tools) {
    if (tool.start_s > last_frame_time_) {
      throw InputError(kSessionWhere, tool.label + ".start_s", "starts after the last recorded frame (t = " +
                                                            exact_number(last_frame_time_) + " s): run the session longer");
    }
    latest_start = std::max(latest_start, tool.start_s);
  }
  for (const ToolAction& tool : recorded_tools()) latest_start = std::max(latest_start, tool.start_s);
  double duration = static_cast<double>(last) * fi;
  if (latest_start >= duration) duration = last_frame_time_ + 0.25 * dt();
  if (static_cast<int64_t>(std::floor(duration / fi + 1e-9)) != last) {
    throw RuntimeError(std::string(kSessionWhere) + ": no duration gives " + std::to_string(last + 1) + " frames (the step " +
                       exact_number(dt()) + " s is too close to the frame interval)");
  }
  return duration;
}

std::string LiveSession::scenario_text(const std::filesystem::path& trajectory_file) const {
  return live_scenario_text(text_, scenario_, recorded_tools(), save_duration(), trajectory_file);
}

Trajectory LiveSession::trajectory() const {
  Trajectory traj = loop_->recorder().snapshot(dt());
  // Tools begun after the last frame: their columns go (the saved scenario leaves them out).
  const ToolTimeline& timeline = loop_->timeline();
  size_t spheres = 0, blades = 0;
  for (size_t i = scenario_.tools.size() + recorded_tools().size(); i < timeline.size(); ++i) {
    ++(timeline.tool(i).type->record == ToolRecord::blade ? blades : spheres);
  }
  const auto drop = [&](std::vector<double>& data, size_t columns, size_t width, size_t dropped) {
    if (dropped == 0) return;
    std::vector<double> kept;
    const size_t frames = traj.time.size();
    for (size_t f = 0; f < frames; ++f) {
      const auto row = data.begin() + static_cast<std::ptrdiff_t>(f * columns * width);
      kept.insert(kept.end(), row, row + static_cast<std::ptrdiff_t>((columns - dropped) * width));
    }
    data = std::move(kept);
  };
  drop(traj.spheres, traj.sphere_kinds.size(), 4, spheres);
  traj.sphere_kinds.resize(traj.sphere_kinds.size() - spheres);
  drop(traj.blades, traj.blades.size() / std::max<size_t>(1, traj.time.size() * 7), 7, blades);
  return traj;
}

void LiveSession::save(const std::filesystem::path& scenario_file, const std::filesystem::path& trajectory_file) const {
  const std::string text = scenario_text(std::filesystem::absolute(trajectory_file));
  const Trajectory traj = trajectory();
  Provenance provenance{"ctsurg-live", kVersion, {kSessionWhere}, {}, nlohmann::json::array()};
  const ModelInputs read = model_inputs(scenario_);
  if (read.grid) provenance.add_input(scenario_.grid);
  if (read.surface) provenance.add_input(scenario_.surface);
  if (read.tetmesh) provenance.add_input(scenario_.tetmesh);
  if (read.centerline) provenance.add_input(scenario_.centerline);
  write_trajectory_file(trajectory_file, traj, provenance);
  write_file_atomically(scenario_file, text);
}

}  // namespace ctsurg::sim
