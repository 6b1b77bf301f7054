// The live session's wire protocol (issue 22): what a browser page sends (JSON text messages, checked
// strictly) and what it receives (JSON text messages and binary frames of the surface), each direction
// a typed message with one codec. No networking here: a server reads a WebSocket text message,
// parse_live_message() turns it into a LiveMessage or refuses it; what it sends back is a
// LiveServerMessage (encode_live_server_message()) or a LiveFrame (encode_live_frame()).
//
// Client -> server: one JSON object per message, at most limits.max_bytes bytes (4 KiB), no other key
// than listed (positions LPS mm, finite, inside the model's rest bounding box enlarged by
// limits.margin_mm; radii (0, 50] mm; a blade's edge (0, 200] mm long; ids 0 .. 2^20):
//
//   {"type": "begin", "tool": "grab" | "probe", "radius_mm": r, "position_mm": [x, y, z]}
//   {"type": "begin", "tool": "cut", "blade_edge_mm": [x, y, z], "position_mm": [x, y, z]}
//   {"type": "move", "id": n, "position_mm": [x, y, z]}       (n: the tool's id, in begin order from 0)
//   {"type": "end", "id": n}
//   {"type": "pause"} | {"type": "resume"} | {"type": "reset"} | {"type": "save"}
//
// Any message may also carry "seq": n (an integer 0 .. 2^32 - 1, the client's own count): the server
// echoes the seq of the last message it had handed to the session in each frame it sends after, so the
// page can time a mouse move to the picture that shows it.
//
// Every refusal is an InputError("message", field, problem) naming the field ("position_mm[2]", "type",
// "(text)" for what is not JSON or too long) and what is wrong; nothing a client sends makes the parser
// crash (tests/sim/live/test_live_protocol.cpp feeds it 20,000 random and mutated messages).
//
// Server -> client, JSON text: one object per message, its keys in alphabetical order (as nlohmann::json
// writes them; the page reads them by name). "seq" is there only when the message it answers had one.
//
//   {"type": "hello", "scenario", "model", "vertex_count", "triangle_count", "bounds": [6], "margin_mm",
//    "dt_s", "colour": [r, g, b], "uvs": bool, "normal_map": null | {"width", "height"},
//    "tools": {"grab_radius_mm", "probe_radius_mm", "cut_depth_mm"},
//    "save_to": null | {"scenario", "trajectory"}, "library", "version"}     (on connecting)
//   {"type": "began", "id": n, "seq"}                     (a begin applied: the tool's id)
//   {"type": "ended", "id": n, "why": text}               (a tool the server let go: reset, stop)
//   {"type": "status", "time_s", "steps", "dt_s", "rtf", "pictures_per_s", "paused", "stopped": text,
//    "halvings", "frames_recorded", "frame_bytes",
//    "loads": [{"id", "force_n": [3], "moment_n_mm": [3]}], "solver_error_mm": mm | null}
//                                                         (about four times a second; loads: each user
//                                                         tool whose load on the tissue the engine measures,
//                                                         SimulationEngine::tool_load; solver_error_mm: the
//                                                         last frame's estimate of how far its solve is from
//                                                         converged, where the model gives one: the
//                                                         engine's metric of that name, FEM quasi-Newton)
//   {"type": "guard", "action": "halved" | "stopped", "message": text}
//   {"type": "error", "message": text, "seq"}             (a message refused)
//   {"type": "saved", "scenario", "trajectory", "frames", "time_s", "seq"}
//   {"type": "closed", "message": text}                   (the last message before the server closes)
//
// Server -> client: a binary frame, little-endian, a 56-byte header then the data:
//
//   offset  bytes  type     field
//        0      4  char[4]  magic "CTLF"
//        4      2  uint16   version, 2
//        6      2  uint16   flags: bit 0 the triangles follow; bit 1 paused; bit 2 stopped (the guard's
//                           message goes as a separate text message)
//        8      8  uint64   frame number (the server's count of frames sent)
//       16      8  float64  simulated time, s
//       24      8  int64    engine steps
//       32      8  uint64   topology version (LiveSession::topology_version(): changes when a cut
//                           changes the triangles)
//       40      4  uint32   V, the surface's vertex count
//       44      4  uint32   F, its triangle count now (whether or not they follow)
//       48      4  uint32   seq: the "seq" of the last client message applied before this frame (0: none)
//       52      4  uint32   0 (padding: the positions start 8-byte aligned)
//       56   12 V  float32  vertex positions x, y, z (LPS mm), vertex by vertex
//   56+12V   12 F  uint32   triangles (3 vertex indices each), only with flag bit 0: the first frame and
//                           whenever the topology version changed since the last frame sent
#pragma once

#include "ctsurg/sim/base/simulation_engine.h"
#include "ctsurg/sim/scenario/tool_type.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace ctsurg::sim {

class LiveSession;

inline constexpr double kMaxLiveToolRadiusMm = 50;  // a grab's or probe's radius, mm
inline constexpr double kMaxLiveBladeMm = 200;      // a blade's edge length, mm

struct LiveMessage {
  enum class Type { begin, move, end, pause, resume, reset, save };
  Type type = Type::pause;
  const ToolType* tool = nullptr;            // begin: a live tool (scenario/tool_type.h: grab, probe, cut)
  double radius_mm = 0;                      // begin grab/probe
  std::array<double, 3> blade_edge_mm{};     // begin cut
  std::array<double, 3> position_mm{};       // begin, move: LPS mm
  int id = -1;                               // move, end
  bool has_seq = false;                      // "seq" given
  uint32_t seq = 0;                          // the client's count (any type)
};

struct LiveProtocolLimits {
  std::array<double, 6> bounds{-1e4, -1e4, -1e4, 1e4, 1e4, 1e4};  // LPS mm: min xyz, max xyz (the model's rest box)
  double margin_mm = 50;        // positions may lie this far outside bounds
  size_t max_bytes = 4096;      // a message's size
  int max_id = 1 << 20;
};

// Parses one client message (see above). InputError("message", field, problem) when it is refused.
LiveMessage parse_live_message(std::string_view text, const LiveProtocolLimits& limits);

struct LiveFrame {
  static constexpr uint16_t kVersion = 2;
  static constexpr size_t kHeaderBytes = 56;
  enum Flags : uint16_t { triangles_follow = 1, paused = 2, stopped = 4 };
  uint16_t flags = 0;
  uint64_t frame = 0;
  double time_s = 0;
  int64_t steps = 0;
  uint64_t topology_version = 0;
  uint32_t triangle_count = 0;       // F
  uint32_t seq = 0;                  // the last applied client message's seq (0: none)
  std::vector<float> positions;      // V x 3, LPS mm
  std::vector<uint32_t> triangles;   // F x 3 when flags has triangles_follow, else empty
};

// Server -> client text messages (layout above). Numbers keep their C++ type on the wire: an integer
// field is written as an integer, a double as a double.
struct LiveHello {
  std::string scenario;                    // the scenario's name
  std::string model;                       // a line saying what the model is
  size_t vertex_count = 0, triangle_count = 0;  // the surface's V and F now
  std::array<double, 6> bounds{};          // the rest box, LPS mm: min xyz, max xyz
  double margin_mm = 0;                    // positions may lie this far outside bounds
  double dt_s = 0;                         // the engine's step, s
  std::array<double, 3> colour{};          // the tissue's colour, linear RGB 0..1
  bool uvs = false;                        // uvs.bin is served
  std::optional<std::array<int, 2>> normal_map;  // normal_map.bin's width and height, when served
  double grab_radius_mm = 0, probe_radius_mm = 0, cut_depth_mm = 0;  // the page's tool defaults
  std::optional<std::array<std::string, 2>> save_to;  // where a save writes: scenario, trajectory
  std::string library;                     // the WebGL library, e.g. "three 0.187.0"
  std::string version;                     // e.g. "ctsurg 0.1.0"
};
struct LiveBegan {
  int id = 0;                              // the tool's id (move and end name it)
  std::optional<uint32_t> seq;             // the begin's seq
};
struct LiveEnded {
  int id = 0;
  std::string why;
};
struct LiveToolLoad {
  int id = 0;                              // the user tool's id
  std::array<double, 3> force_n{};         // on the tissue, N (LPS)
  std::array<double, 3> moment_n_mm{};     // about the tool's centre, N mm
};
struct LiveStatus {
  double time_s = 0;                       // simulated
  int64_t steps = 0;
  double dt_s = 0;
  double rtf = 0;                          // simulated s per wall s over the last ~second
  double pictures_per_s = 0;               // frames written to the socket over the last ~second
  bool paused = false;
  std::string stopped;                     // the guard's message when it stopped the session, else ""
  int halvings = 0;                        // step halvings so far
  int64_t frames_recorded = 0;
  size_t frame_bytes = 0;                  // the last frame's size
  std::vector<LiveToolLoad> loads;         // the user tools' measured loads now
  double solver_error_mm = NAN;            // the last frame's estimate of its solver error (FEM quasi-Newton), else NaN
};
struct LiveGuard {
  enum class Action { halved, stopped };   // the step was halved (the session goes on) | the session stopped
  Action action = Action::halved;
  std::string message;
};
struct LiveError {
  std::string message;                     // InputError's text: field and problem
  std::optional<uint32_t> seq;             // the refused message's seq, when it was read
};
struct LiveSaved {
  std::string scenario, trajectory;        // the files written
  int64_t frames = 0;                      // recorded frames
  double time_s = 0;                       // simulated
  std::optional<uint32_t> seq;             // the save's seq
};
struct LiveClosed {
  std::string message;                     // why the server closes the socket
};
using LiveServerMessage =
    std::variant<LiveHello, LiveBegan, LiveEnded, LiveStatus, LiveGuard, LiveError, LiveSaved, LiveClosed>;

// The message's JSON text (layout above), what the server sends as one WebSocket text message.
std::string encode_live_server_message(const LiveServerMessage& message);

// The frame's bytes (layout above); triangles are written when flags has triangles_follow.
std::vector<uint8_t> encode_live_frame(const LiveFrame& frame);
// The frame back from its bytes: InputError("frame", field, problem) for a wrong magic or version, a
// size that does not match the counts, or triangle indices beyond V.
LiveFrame decode_live_frame(std::span<const uint8_t> bytes);

// The session's surface now as frame number `frame`; the triangles follow when its topology version
// differs from `sent_topology` (the version of the last frame sent; 0 for the first: versions start at 1).
LiveFrame live_frame_of(LiveSession& session, uint64_t frame, uint64_t sent_topology);

}  // namespace ctsurg::sim
