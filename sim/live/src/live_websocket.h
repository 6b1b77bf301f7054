// ctsurg-live's WebSockets (issue 22): the page's socket under /<token>/ws, after live_http.h has
// checked its upgrade request. Everything here runs on the networking thread except post_text and
// post_frame, which the simulation thread calls (they hand the write to the networking thread).
//
// Reads: each text message goes to the inbox (live_inbox.h) for the session pump; a binary one, or one
// beyond the inbox's limit, is answered with an error ("(binary)", "(queue)"); one over
// LiveServer::kMaxSocketMessageBytes closes the socket (1009). Writes, per socket: text messages in
// order, then the newest frame: a frame waiting while the previous one is written is replaced by a
// newer one (it takes over the triangles the replaced one carried), so a slow page sees fewer pictures,
// not older ones.
//
// One socket controls the session: a newly opened one takes over, and the previous one is told why
// ("closed") and closed (close code 1008, policy); what it still sends is not applied.
#pragma once

#include "ctsurg/sim/live/live_protocol.h"
#include "live_inbox.h"
#include "live_server_counters.h"

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/http/message.hpp>
#include <boost/beast/http/string_body.hpp>

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>

namespace ctsurg::sim {

class LiveSocket;

class LiveSockets {
 public:
  LiveSockets(boost::asio::io_context& io, LiveInbox& inbox, LiveServerCounters& counters,
              const std::function<void(const std::string&)>& log)
      : io_(io), inbox_(inbox), counters_(counters), log_(log) {}

  // Networking thread: completes the WebSocket handshake of an upgrade request that live_http.h let
  // through; the socket then controls the session (the inbox gets "opened").
  void open(boost::asio::ip::tcp::socket socket, boost::beast::http::request<boost::beast::http::string_body> request);

  // Any thread: to socket `id` (the inbox's LiveInbound::socket), if it is still open. `text` is one
  // JSON message (encode_live_server_message); `input`: when the oldest message the frame answers arrived.
  void post_text(uint64_t id, std::string text);
  void post_frame(uint64_t id, LiveFrame frame, LiveInputTime input);

 private:
  friend class LiveSocket;
  // Networking thread, from LiveSocket.
  void handshake_done(uint64_t id, std::weak_ptr<LiveSocket> socket);
  void closed(uint64_t id);
  bool controls(uint64_t id) const { return controller_ == id; }

  boost::asio::io_context& io_;
  LiveInbox& inbox_;
  LiveServerCounters& counters_;
  const std::function<void(const std::string&)>& log_;
  std::map<uint64_t, std::weak_ptr<LiveSocket>> sockets_;
  uint64_t next_socket_ = 1, controller_ = 0;  // controller_: the socket that controls the session (0: none)
};

}  // namespace ctsurg::sim
