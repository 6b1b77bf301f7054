// ctsurg-live's simulation thread (issue 22): it owns the LiveSession while the server runs. Each tick
// (1/picture_hz of wall time):
//   1. the inbox's events (live_inbox.h), in arrival order: a socket opened (it gets "hello"; the tools
//      the previous page held end; a session paused by a page leaving resumes), closed (its tools end;
//      the session pauses once that is applied), or a page message, parsed (parse_live_message) and
//      applied at the session's step boundary, or refused with an "error";
//   2. the session advanced by what LiveClock owes it (LiveSession::advance), with a "guard" message when
//      the stability guard halved the step or stopped the session (a stop also ends the page's tools);
//   3. a frame when something changed (the session advanced, its topology or its paused/stopped flags),
//      with the seq of the last page message applied; the triangles only with a new topology;
//   4. a "status" message at most every 250 ms;
//   5. sleep for the rest of the tick.
// Messages and frames go to the controlling socket only (live_websocket.h), typed
// (live_protocol.h's LiveServerMessage), encoded here, written by the networking thread.
#pragma once

#include "ctsurg/sim/live/live_clock.h"
#include "ctsurg/sim/live/live_protocol.h"
#include "ctsurg/sim/live/live_server.h"
#include "ctsurg/sim/live/live_session.h"
#include "live_inbox.h"
#include "live_server_counters.h"
#include "live_websocket.h"

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <string>

namespace ctsurg::sim {

class LiveSessionPump {
 public:
  // Construct it on the simulation thread, when the session is to start: the pacing and the status's
  // windows start now. `stopping` ends run(); `unsaved` is set by a user change and cleared by a save.
  LiveSessionPump(LiveSession& session, const LiveServerOptions& options, LiveInbox& inbox, LiveSockets& sockets,
                  LiveServerCounters& counters, const std::function<void(const std::string&)>& log,
                  const std::atomic<bool>& stopping, std::atomic<bool>& unsaved);

  // Ticks until `stopping`. An InputError from parsing or applying a page's message is answered with
  // "error" and the pump goes on; any other exception ends run() (LiveServer::run rethrows it).
  void run();

 private:
  void take_inbox();
  void socket_opened(uint64_t socket);
  void socket_closed(uint64_t socket);
  void apply(const LiveMessage& m);
  // Ends the user tools that `owner` began (0: every page's), telling the page why when `tell`.
  void end_tools(uint64_t owner, const std::string& why, bool tell);
  // Advances the session by what the clock owes it; the simulated and the wall seconds that took.
  LiveAdvance advance();
  void send_picture(double advanced);
  void send_status();
  void send(LiveServerMessage message);
  LiveHello hello();

  LiveSession& session_;
  const LiveServerOptions& options_;
  LiveInbox& inbox_;
  LiveSockets& sockets_;
  LiveServerCounters& counters_;
  const std::function<void(const std::string&)>& log_;
  const std::atomic<bool>& stopping_;
  std::atomic<bool>& unsaved_;

  LiveProtocolLimits limits_;
  uint64_t current_ = 0;                   // the socket that controls the session (0: none)
  uint64_t sent_topology_ = 0;             // the topology of the last frame sent to it
  uint64_t frame_number_ = 0;
  uint32_t last_seq_ = 0;                  // the last message's seq handed to the session
  std::map<int, uint64_t> tools_;          // user tools not ended -> the socket that began them
  bool paused_by_leaving_ = false;
  LiveInputTime input_;                    // the oldest message handled since the last frame
  uint16_t last_flags_ = 0;
  LiveClock clock_;
  int last_halvings_;
  // The status line: real-time factor and pictures over the last ~second.
  LiveWallClock::time_point window_start_;
  double window_sim_ = 0;
  uint64_t window_frames_;
  double rtf_ = 0, pictures_per_s_ = 0;
  LiveWallClock::time_point last_status_;
  size_t last_frame_bytes_ = 0;
};

}  // namespace ctsurg::sim
