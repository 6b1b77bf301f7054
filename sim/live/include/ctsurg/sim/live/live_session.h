// A live rehearsal (issue 22): a scenario's model driven by a user's tools in real time, recorded so
// that ctsurg-sim replays it to the same trajectory.
//
// Model. Built from a Scenario exactly as ctsurg-sim builds it (make_scenario_engine: the same files,
// material, fixed regions, step, backend); the scenario's own tools (`tools:`, may be empty) act as in
// a run. The session owns a ScenarioLoop (scenario/scenario_run.h), the runner's own loop, and
// advances it an event at a time: one step of dt (several while no tool acts, for an engine that
// batches them: FEM dynamic), or a quasi-static engine's equilibrium at the next frame.
//
// Tools. begin_tool() (grab, probe or cut), move_tool() (an LPS position, mm) and end_tool() are
// queued and applied at the next event boundary, between two advances of the loop. A boundary at time
// t whose next event ends at t1 (ScenarioLoop::next_time(): t + dt) turns them into the timeline's
// terms: a tool begun there has start_s = t1 and a keyframe (t1, position); a move adds a keyframe
// (t, the position it had) unless its last keyframe is at t, then (max(t1, t + move_ramp_s()), new
// position) (a second move at the same boundary replaces it); an end sets end_s = t1 (a tool begun and
// ended at one boundary acts for one event). The ramp (set_move_ramp_s; ctsurg-live sets one picture
// tick of simulated time) lets a tool travel between two of the page's messages instead of jumping in
// one step: a fast mouse moves 3 mm between messages, which in one 0.17 ms step of the spring bar is
// 17 m/s and trips the stability guard. Events queued during a ramp wait until it ends (below). Linear interpolation between keyframes at step times then gives exactly the
// positions the user gave (a + 0 * (b - a) = a in floating point; at and after the last key, the key
// itself), so the runner, reading the same keyframes, computes the same ToolInputs at every step, the
// same blade sweeps and the same idle intervals (batching); the loop is shared, so the stability checks,
// restarts and frame times are too. Replay is therefore bit-identical (tests/sim/live).
//
// Stability. An unstable step restarts from the last frame with half the step while the scenario's
// time.max_step_halvings allows (the runner does the same at the same step, so the replay still
// matches; restart_message() keeps the guard's message). Tool events queued meanwhile wait until the
// loop is back past the user's last keyframe (that part of the recording is already written). Beyond
// that, or when the engine refuses a tool (a grab that holds no free particle), the session goes back
// to its last frame, drops the tool events after it, pauses and keeps the message (stopped_message()):
// "the state before it". A ramp under way at that frame is cut there: it ends at the frame, at the
// position it had reached (interpolated, so the frames replayed up to it may differ from those shown
// in the last bits of float rounding; without a ramp they are the same bits). Going back rebuilds the engine and replays the recording up to that frame
// (deterministic, so the state is the one it had; it costs the time the session has run, at batch
// speed). Tool ids past the tools kept are given out again.
//
// Recording. Frames are recorded as the runner records them (trajectory_recorder.h: at t = 0 and every
// frame_interval_s). scenario_text() is the scenario (its own text, with the model's files made
// absolute, time.duration_s ending at the last recorded frame, output.frame_interval_s written out)
// with the user's tools appended to `tools:` (kind, radius_mm / blade_edge_mm, start_s, end_s and path
// keyframes {t, position_mm}, numbers as %.17g so they parse back to the same doubles); trajectory()
// the frames recorded so far. ctsurg-sim on that text writes that trajectory.
//
// Memory: the recording stays in memory, 12 V bytes a frame (V surface vertices: 179 KB on the heart).
// Threads: one thread drives a session (the engine may use OpenMP inside a call).
//
// Units: mm (LPS), s. Positions given and returned are LPS; the engine runs in its local frame
// (LPS minus origin()).
#pragma once

#include "ctsurg/core/trajectory_file.h"
#include "ctsurg/sim/live/live_protocol.h"
#include "ctsurg/sim/scenario/scenario.h"
#include "ctsurg/sim/scenario/scenario_run.h"

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace ctsurg::sim {

// A tool the user begins: grab or probe (a sphere of radius_mm), or cut (a blade with edge
// blade_edge_mm, centred on its position); at `position_mm` (LPS).
struct LiveToolSpec {
  const ToolType* kind = nullptr;        // a live tool (scenario/tool_type.h: ToolType::live)
  double radius_mm = 0;                  // grab, probe: (0, kMaxLiveToolRadiusMm]
  std::array<double, 3> blade_edge_mm{}; // cut: length in (0, kMaxLiveBladeMm]
  std::array<double, 3> position_mm{};   // LPS mm, finite
};

// The tool a page's begin message asks for (live_protocol.h).
inline LiveToolSpec live_tool_spec(const LiveMessage& m) { return {m.tool, m.radius_mm, m.blade_edge_mm, m.position_mm}; }

// What advance() did.
struct LiveAdvance {
  int64_t events = 0;     // loop events (steps, batches or equilibria)
  int64_t frames = 0;     // frames recorded
  double sim_s = 0;       // simulated time advanced, s
  double wall_s = 0;      // seconds it took
  bool restarted = false; // a step halving happened (restart_message())
  bool stopped = false;   // the session went back to its last frame and paused (stopped_message())
};

class LiveSession {
 public:
  // scenario: parsed (read_scenario_file or parse_scenario); text: the YAML it was parsed from (the
  // saved scenario is this text with the user's tools). note receives what the engine decides.
  LiveSession(Scenario scenario, std::string text, std::function<void(const std::string&)> note = {});
  ~LiveSession();
  LiveSession(const LiveSession&) = delete;  // its loop refers to its scenario
  LiveSession& operator=(const LiveSession&) = delete;

  // Tool events, applied at the next event boundary. begin_tool returns the tool's id (0, 1, ... in
  // the order begun). InputError("live session", field, problem) for a bad kind, radius, blade or a
  // non-finite position; move_tool / end_tool on an unknown or ended tool likewise.
  int begin_tool(const LiveToolSpec& spec);
  void move_tool(int id, const std::array<double, 3>& position_mm);
  void end_tool(int id);
  bool tool_active(int id) const;  // begun and not ended (pending events included)
  // Simulated seconds over which a move reaches its position (above); 0, the default: at the next
  // event's end. InputError unless finite and >= 0.
  void set_move_ramp_s(double seconds);
  double move_ramp_s() const { return move_ramp_s_; }

  void pause() { paused_ = true; }
  void resume();  // also clears a stop
  bool paused() const { return paused_; }
  // A new engine from the scenario, no user tools, the recording restarted; paused state kept.
  void reset();

  // Runs loop events until the simulated time has advanced by wall_seconds x realtime_factor or
  // wall_seconds of wall time are spent (then the backlog is dropped: the real-time factor achieved is
  // sim_s / wall_s). Nothing while paused.
  LiveAdvance advance(double wall_seconds, double realtime_factor = 1.0);
  // Runs n loop events (tests, benchmarks), or fewer when the session stops.
  LiveAdvance advance_events(int64_t n);

  // State.
  double time() const;             // simulated s
  int64_t steps() const;           // engine steps
  double dt() const;               // s
  int halvings() const;            // step halvings so far
  int64_t frames() const;          // recorded frames
  const std::string& restart_message() const { return restart_message_; }  // the last halving's guard message
  const std::string& stopped_message() const { return stopped_message_; }  // empty while running
  const SimulationEngine& engine() const;
  // The loads the user's tools exert on the tissue now (those the engine measures: SimulationEngine::tool_load).
  std::vector<LiveToolLoad> tool_loads() const;
  // The last frame's estimate of its solver error (mm): the engine's metric solver_error_mm as the
  // recorder recorded it (FEM static quasi-Newton, fem_static_solver.h FemStaticReport::error_estimate_mm),
  // NaN for a model without one.
  double solver_error_mm() const;
  const Scenario& scenario() const { return scenario_; }

  // The surface now: vertices (#V x 3 LPS mm, float as the trajectory stores them), triangles
  // (#F x 3), and a counter that changes whenever the triangles change (a cut).
  void surface(std::vector<float>& lps);
  const std::vector<uint32_t>& triangles() const;
  uint64_t topology_version() const { return topology_version_; }
  // The tissue's rest bounding box (LPS mm): what positions are checked against (live_protocol.h).
  std::array<double, 6> rest_bounds() const;

  // The recording (see above): the scenario text whose run writes `trajectory_file` (its
  // output.trajectory; relative to where the scenario is saved), and the frames so far. Both need a
  // frame after the rest frame. InputError when a scenario tool starts after the last frame.
  std::string scenario_text(const std::filesystem::path& trajectory_file) const;
  Trajectory trajectory() const;
  // Writes both (the trajectory as ctsurg-sim writes it, provenance naming this session).
  void save(const std::filesystem::path& scenario_file, const std::filesystem::path& trajectory_file) const;

 private:
  struct Pending;
  void build(const std::vector<ToolAction>& user_tools, int64_t replay_frames);
  void apply_pending();
  void go_back(const std::string& why);
  void track_topology();
  double save_duration() const;
  std::vector<ToolAction> recorded_tools() const;

  Scenario scenario_;        // as given (its own tools)
  std::string text_;
  std::function<void(const std::string&)> note_;
  Scenario loop_scenario_;   // the loop's: the scenario with the user tools it was (re)built with
  std::unique_ptr<ScenarioLoop> loop_;
  std::vector<bool> ended_;  // per user tool (by id): an end was queued or applied
  double last_frame_time_ = 0;  // s, the last recorded frame's
  double move_ramp_s_ = 0;      // s, set_move_ramp_s
  std::vector<Pending> pending_;
  bool paused_ = false;
  std::string restart_message_, stopped_message_;
  std::vector<uint32_t> last_triangles_;
  uint64_t topology_version_ = 0;
};

}  // namespace ctsurg::sim
