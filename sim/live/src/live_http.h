// ctsurg-live's HTTP side (issue 22; docs/live.md, "Safe by default"): one connection's requests, the
// page's files under /<token>/, and the checks a WebSocket's upgrade request passes before it becomes
// the session's socket (live_websocket.h). Runs on the networking thread.
//
// - Everything lives under /<token>/ (the token: 128 random bits as 32 hex digits, compared in constant
//   time); any other path gets 404 with nothing about the session. A query ("?x=1") is ignored.
// - The Host header must name this server (LiveHttpSite::allowed_hosts; stops DNS rebinding): else 421.
// - Only GET and HEAD (else 405); request headers at most 8 KiB, bodies 4 KiB (else 400 and closed); an
//   idle connection is closed after 30 s.
// - Files are served with a Content-Security-Policy that allows nothing but this origin, no-store,
//   nosniff, no framing and no referrer.
// - A WebSocket upgrade must be for /<token>/ws, from this server's own page (Origin http://<Host>):
//   else 403 with the reason, which the log also gets.
#pragma once

#include "live_server_counters.h"

#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/http/message.hpp>
#include <boost/beast/http/string_body.hpp>

#include <cstdint>
#include <functional>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <string_view>

namespace ctsurg::sim {

// 128 bits from the system's random source, as 32 lowercase hex digits.
std::string live_random_token();

// What the HTTP side serves and to whom.
struct LiveHttpSite {
  std::string token;
  std::set<std::string> allowed_hosts;   // Host header values ("127.0.0.1:8080"); empty: any (all addresses)
  std::span<const float> uvs;            // uvs.bin: V x 2 (empty: not served)
  std::span<const uint8_t> normal_map_rgba;  // normal_map.bin: RGBA8 (empty: not served)

  bool host_allowed(std::string_view host) const;
  // The part of `target` after "/<token>/" (its query left off), or nullopt when it is not under the token.
  std::optional<std::string_view> under_token(std::string_view target) const;
};

using LiveUpgradeRequest = boost::beast::http::request<boost::beast::http::string_body>;

// `open_socket` receives a checked WebSocket upgrade request with its TCP socket.
using LiveOpenSocket = std::function<void(boost::asio::ip::tcp::socket, LiveUpgradeRequest)>;

// Serves one accepted TCP connection: reads its requests and answers them (while the client keeps it
// alive) until it closes, idles 30 s, sends a bad request, or upgrades to the WebSocket. `site`,
// `counters` and `log` must outlive the connection (the server's own members).
void live_http_serve(boost::asio::ip::tcp::socket socket, const LiveHttpSite& site, LiveServerCounters& counters,
                     const std::function<void(const std::string&)>& log, LiveOpenSocket open_socket);

}  // namespace ctsurg::sim
