// LiveServer (live_server.h): the owner that wires ctsurg-live's parts together and runs them.
//   live_http.h          HTTP: the page's files, the token, the Host and Origin checks
//   live_websocket.h     the WebSockets: reads into the inbox, writes texts and the newest frame
//   live_inbox.h         networking thread -> simulation thread
//   live_session_pump.h  the simulation thread: messages applied, stepping, pacing, frames, status
//   live_server_counters.h  what stats() reports
// The networking (Boost.Asio, one io_context) runs on run()'s calling thread; the pump on a thread of
// its own that run() starts and joins.
#include "ctsurg/sim/live/live_server.h"

#include "ctsurg/core/error.h"
#include "live_http.h"
#include "live_inbox.h"
#include "live_server_counters.h"
#include "live_session_pump.h"
#include "live_websocket.h"

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/signal_set.hpp>

#include <atomic>
#include <csignal>
#include <exception>
#include <optional>
#include <thread>

namespace ctsurg::sim {

namespace asio = boost::asio;
using tcp = asio::ip::tcp;

namespace {

std::string listen_host_text(const asio::ip::address& address, uint16_t port) {
  const std::string a = address.to_string();
  return (address.is_v6() ? "[" + a + "]" : a) + ":" + std::to_string(port);
}

}  // namespace

// The server's parts. The io_context, the acceptor and the sockets are the networking thread's; the
// session is the pump's while run() runs; the inbox, the counters and the flags are shared.
struct LiveServer::Impl {
  LiveSession& session;
  LiveServerOptions options;
  std::function<void(const std::string&)> log;
  asio::io_context io{1};
  tcp::acceptor acceptor{io};
  std::optional<asio::signal_set> signals;
  uint16_t port = 0;
  std::string url;
  LiveHttpSite site;
  LiveServerCounters counters;
  LiveInbox inbox{kMaxQueuedMessages};
  LiveSockets sockets{io, inbox, counters, log};
  std::atomic<bool> stopping{false};
  std::atomic<bool> unsaved{false};
  std::exception_ptr failure;

  Impl(LiveSession& s, LiveServerOptions o, std::function<void(const std::string&)> l)
      : session(s), options(std::move(o)), log(std::move(l)) {
    if (!log) log = [](const std::string&) {};
  }

  // Binds options.host:options.port; the Host names the HTTP side answers to; the page's URL.
  void listen() {
    boost::system::error_code ec;
    const asio::ip::address address = asio::ip::make_address(options.host, ec);
    if (ec) throw InputError(options.host, "--host", "not a numeric IPv4 or IPv6 address (" + ec.message() + ")");
    const tcp::endpoint endpoint(address, options.port);
    acceptor.open(endpoint.protocol(), ec);
    if (!ec) acceptor.set_option(asio::socket_base::reuse_address(true), ec);
    if (!ec) acceptor.bind(endpoint, ec);
    if (!ec) acceptor.listen(asio::socket_base::max_listen_connections, ec);
    if (ec) {
      throw InputError(listen_host_text(address, options.port), "--port", "cannot listen there: " + ec.message());
    }
    port = acceptor.local_endpoint().port();
    if (!address.is_unspecified()) {
      site.allowed_hosts.insert(listen_host_text(address, port));
      if (address.is_loopback()) site.allowed_hosts.insert("localhost:" + std::to_string(port));
    }
    const std::string shown = address.is_unspecified() ? (address.is_v6() ? "[::1]" : "127.0.0.1") : "";
    url = "http://" + (shown.empty() ? listen_host_text(address, port) : shown + ":" + std::to_string(port)) + "/" +
          site.token + "/";
  }

  // Each connection to the HTTP side; a checked upgrade request to the sockets.
  void accept() {
    acceptor.async_accept([this](boost::system::error_code ec, tcp::socket socket) {
      if (ec) {
        if (ec != asio::error::operation_aborted) log("live: accept failed: " + ec.message());
      } else {
        live_http_serve(std::move(socket), site, counters, log,
                        [this](tcp::socket s, LiveUpgradeRequest request) { sockets.open(std::move(s), std::move(request)); });
      }
      if (!stopping) accept();
    });
  }
};

LiveServer::LiveServer(LiveSession& session, LiveServerOptions options, std::function<void(const std::string&)> log)
    : impl_(std::make_unique<Impl>(session, std::move(options), std::move(log))) {
  LiveServerOptions& o = impl_->options;
  if (!(o.picture_hz >= 1 && o.picture_hz <= 240)) {
    throw InputError("live server", "--picture-rate", std::to_string(o.picture_hz) + " is outside 1 .. 240 per second");
  }
  if (!(o.realtime_factor > 0 && o.realtime_factor <= 100)) {
    throw InputError("live server", "--realtime-factor", std::to_string(o.realtime_factor) + " is outside (0, 100]");
  }
  std::vector<float> lps;
  session.surface(lps);
  if (!o.uvs.empty() && o.uvs.size() != 2 * (lps.size() / 3)) {
    throw InputError("live server", "uvs", std::to_string(o.uvs.size() / 2) + " texture coordinates for " +
                                               std::to_string(lps.size() / 3) + " surface vertices");
  }
  if (!o.normal_map_rgba.empty() &&
      o.normal_map_rgba.size() != 4 * static_cast<size_t>(o.normal_map_width) * static_cast<size_t>(o.normal_map_height)) {
    throw InputError("live server", "normal map", "its bytes do not match its size");
  }
  LiveHttpSite& site = impl_->site;
  site.token = o.token.empty() ? live_random_token() : o.token;
  if (site.token.size() < 16 || site.token.find_first_not_of("0123456789abcdefghijklmnopqrstuvwxyz") != std::string::npos) {
    throw InputError("live server", "token", "at least 16 characters, lowercase letters and digits only");
  }
  site.uvs = o.uvs;
  site.normal_map_rgba = o.normal_map_rgba;
  impl_->listen();
  if (o.stop_on_signals) {
    impl_->signals.emplace(impl_->io, SIGINT, SIGTERM);
    impl_->signals->async_wait([this](boost::system::error_code ec, int) {
      if (!ec) stop();
    });
  }
}

LiveServer::~LiveServer() { stop(); }

std::string LiveServer::url() const { return impl_->url; }
uint16_t LiveServer::port() const { return impl_->port; }
const std::string& LiveServer::token() const { return impl_->site.token; }
bool LiveServer::unsaved() const { return impl_->unsaved; }
LiveServerStats LiveServer::stats() const { return impl_->counters.stats(); }

void LiveServer::run() {
  Impl& i = *impl_;
  i.accept();
  std::thread simulation([&i] {
    try {
      LiveSessionPump pump(i.session, i.options, i.inbox, i.sockets, i.counters, i.log, i.stopping, i.unsaved);
      pump.run();
    } catch (...) {
      i.failure = std::current_exception();
      i.stopping = true;
      i.io.stop();
    }
  });
  i.io.run();
  i.stopping = true;
  simulation.join();
  if (i.failure) std::rethrow_exception(i.failure);
}

void LiveServer::stop() {
  impl_->stopping = true;
  impl_->io.stop();
}

}  // namespace ctsurg::sim
