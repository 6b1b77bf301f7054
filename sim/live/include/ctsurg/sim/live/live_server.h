// ctsurg-live's web server (issue 22): serves the live page (sim/live/page, embedded at build time)
// and runs one LiveSession in real time for the browser that opens it. Its parts, in sim/live/src:
// live_http.h (HTTP and its checks), live_websocket.h (the sockets), live_session_pump.h (the
// simulation thread); live_server.cpp wires them. What goes over the socket is typed both ways
// (live_protocol.h).
//
// Threads. The calling thread of run() does the networking (Boost.Asio, one thread: HTTP requests and
// WebSocket reads and writes). A simulation thread owns the session: it takes the page's messages
// from a queue, applies them at the session's step boundaries, advances the session by 1/picture_hz
// of wall time at a time (LiveSession::advance: the real-time factor is what it reaches), and hands
// each picture's frame to the networking thread. A socket whose previous frame is still being written
// gets only the newest one (frames in between are dropped, never queued), so a slow browser sees
// fewer pictures, not older ones.
//
// Safety (docs/live.md, "Safe by default"):
// - Listens on options.host (127.0.0.1 unless told otherwise).
// - Everything lives under /<token>/: the page, its scripts and the socket. The token is 128 random
//   bits (32 hex digits), compared in constant time; any other path gets 404 with nothing about the
//   session.
// - The Host header must name this server (the address it listens on, or localhost for a loopback
//   address; stops DNS rebinding); a WebSocket's Origin must be this server's own origin.
// - Only GET and HEAD; request headers are at most 8 KiB; the page is served with a Content-Security-
//   Policy that allows nothing but this origin. The page reads no file: the only files written are
//   the session's save paths, fixed on the command line.
// - Socket messages: text only, at most 64 KiB (larger: the socket is closed, 1009 "message too
//   big"); each is checked by parse_live_message and a refused one is answered {"type": "error", ...}.
//   At most kMaxQueuedMessages wait for the simulation; beyond that they are refused as "busy".
// - One browser controls the session at a time: a second one that connects takes it over (the first
//   is told why and closed), and the tools the first was holding are ended, as when a browser closes
//   mid-drag. Nothing recorded is lost either way.
#pragma once

#include "ctsurg/sim/live/live_session.h"

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace ctsurg::sim {

struct LiveServerOptions {
  std::string host = "127.0.0.1";  // address to listen on (numeric IPv4 or IPv6)
  uint16_t port = 0;               // 0: a free port chosen by the system
  std::string token;               // empty: 128 random bits as 32 hex digits (tests may fix it)
  std::filesystem::path save_scenario, save_trajectory;  // where a "save" writes (required to save)
  double picture_hz = 60;          // pictures a second sent to the page (and the simulation's tick)
  double realtime_factor = 1;      // simulated seconds per wall second aimed at
  double grab_radius_mm = 8, probe_radius_mm = 6, cut_depth_mm = 15;  // the page's tool defaults
  double margin_mm = 50;           // positions may lie this far outside the rest box
  // The surface's texture atlas (#V x 2, u right, v down; empty: none) and tangent-space normal map
  // (RGBA8, rows top first; empty: none), served to the page as uvs.bin and normal_map.bin; the
  // tissue's colour (linear RGB) and a line saying what the model is.
  std::vector<float> uvs;
  int normal_map_width = 0, normal_map_height = 0;
  std::vector<uint8_t> normal_map_rgba;
  std::array<double, 3> colour{0.55, 0.12, 0.10};
  std::string model_description;
  bool stop_on_signals = false;    // SIGINT and SIGTERM end run() (the tool; not tests)
};

struct LiveServerStats {
  uint64_t frames_sent = 0, frame_bytes_sent = 0, messages = 0, refused_messages = 0;
  uint64_t http_requests = 0, refused_requests = 0, sockets_opened = 0, sockets_taken_over = 0;
  uint64_t saves = 0;
  // Per picture that answered a page's message: ms from the message's arrival to the picture's last
  // byte handed to the socket (the server's share of the latency; the page measures the whole).
  std::vector<double> input_to_picture_ms;
};

class LiveServer {
 public:
  static constexpr size_t kMaxSocketMessageBytes = 64 * 1024;
  static constexpr size_t kMaxQueuedMessages = 4096;

  // Binds and listens (InputError("--host"/"--port", ...) when it cannot); nothing runs until run().
  // `log` receives one line per event worth telling the terminal (connections, saves, refusals).
  LiveServer(LiveSession& session, LiveServerOptions options, std::function<void(const std::string&)> log = {});
  ~LiveServer();
  LiveServer(const LiveServer&) = delete;
  LiveServer& operator=(const LiveServer&) = delete;

  // The page's address, token included: http://HOST:PORT/TOKEN/
  std::string url() const;
  uint16_t port() const;
  const std::string& token() const;

  // Serves and simulates until stop() (from any thread or a signal handler's thread) or a fatal
  // error. The session belongs to the simulation thread meanwhile: touch it only after run() returns.
  void run();
  void stop();
  // Whether the user changed the session (a tool, a reset) since it was last saved.
  bool unsaved() const;
  LiveServerStats stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ctsurg::sim
