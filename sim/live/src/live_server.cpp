#include "ctsurg/sim/live/live_server.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/version.h"
#include "ctsurg/sim/live/live_clock.h"
#include "ctsurg/sim/live/live_protocol.h"
#include "live_page_assets.h"

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <nlohmann/json.hpp>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <exception>
#include <map>
#include <mutex>
#include <optional>
#include <random>
#include <set>
#include <thread>

namespace ctsurg::sim {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

namespace {

// 128 bits from the system's random source, as 32 lowercase hex digits.
std::string random_token() {
  std::random_device device;  // /dev/urandom on Linux
  std::string token;
  for (int k = 0; k < 4; ++k) {
    char part[9];
    std::snprintf(part, sizeof part, "%08x", static_cast<unsigned>(device()));
    token += part;
  }
  return token;
}

// Constant-time comparison (the time does not tell how many leading characters were right).
bool same_secret(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (size_t k = 0; k < a.size(); ++k) diff |= static_cast<unsigned char>(a[k] ^ b[k]);
  return diff == 0;
}

// Beast's header values and targets (boost::string_view) as std::string_view.
std::string_view view(beast::string_view v) { return {v.data(), v.size()}; }

std::string host_text(const asio::ip::address& address, uint16_t port) {
  const std::string a = address.to_string();
  return (address.is_v6() ? "[" + a + "]" : a) + ":" + std::to_string(port);
}

// A frame waiting for its socket: when a newer one replaces it unsent, the triangles it carried move
// to the newer one (same topology: the simulation sends the triangles only with the first frame of a
// topology), so the page never misses a topology change.
void supersede(std::optional<LiveFrame>& waiting, LiveFrame next) {
  if (waiting && (waiting->flags & LiveFrame::triangles_follow) && !(next.flags & LiveFrame::triangles_follow) &&
      waiting->topology_version == next.topology_version) {
    next.triangles = std::move(waiting->triangles);
    next.flags |= LiveFrame::triangles_follow;
  }
  waiting = std::move(next);
}

}  // namespace

// ---------------------------------------------------------------------------------------------------
// The server's state. Networking members are touched by the I/O thread only; the session and the
// simulation's bookkeeping by the simulation thread only; the inbox and the counters are shared.

struct LiveServer::Impl {
  struct Inbound {
    enum class Kind { opened, message, closed } kind;
    uint64_t socket = 0;
    std::string text;
    Clock::time_point received = Clock::now();
  };
  using Input = std::optional<Clock::time_point>;  // when the oldest message a frame answers arrived
  class Socket;
  class HttpConnection;

  LiveSession& session;
  LiveServerOptions options;
  std::function<void(const std::string&)> log;
  std::string token;
  asio::io_context io{1};
  tcp::acceptor acceptor{io};
  std::optional<asio::signal_set> signals;
  uint16_t port = 0;
  std::set<std::string> allowed_hosts;  // Host header values; empty: any (listening on all addresses)
  std::string url;

  // I/O thread.
  std::map<uint64_t, std::weak_ptr<Socket>> sockets;
  uint64_t next_socket = 1, controller = 0;

  // Shared.
  std::mutex inbox_mutex;
  std::deque<Inbound> inbox;
  std::atomic<bool> stopping{false};
  std::atomic<bool> unsaved{false};
  std::atomic<uint64_t> frames_sent{0}, frame_bytes_sent{0}, messages{0}, refused_messages{0}, http_requests{0},
      refused_requests{0}, sockets_opened{0}, sockets_taken_over{0}, saves{0};
  std::exception_ptr failure;
  std::mutex latency_mutex;
  std::vector<double> latencies_ms;

  Impl(LiveSession& s, LiveServerOptions o, std::function<void(const std::string&)> l)
      : session(s), options(std::move(o)), log(std::move(l)) {
    if (!log) log = [](const std::string&) {};
  }

  void say(const std::string& line) { log(line); }

  // I/O thread -> simulation thread.
  bool push(Inbound in) {
    std::lock_guard lock(inbox_mutex);
    if (in.kind == Inbound::Kind::message && inbox.size() >= kMaxQueuedMessages) return false;
    inbox.push_back(std::move(in));
    return true;
  }
  std::deque<Inbound> take_inbox() {
    std::lock_guard lock(inbox_mutex);
    return std::exchange(inbox, {});
  }

  // Simulation thread -> I/O thread (to the socket `id`, if it is still open).
  void send_text(uint64_t id, std::string text);
  void send_frame(uint64_t id, LiveFrame frame, Input input);
  // I/O thread: a frame answering a message that arrived at `input` was written.
  void picture_written(Clock::time_point input) {
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - input).count();
    std::lock_guard lock(latency_mutex);
    if (latencies_ms.size() >= 100000) latencies_ms.erase(latencies_ms.begin(), latencies_ms.begin() + 50000);
    latencies_ms.push_back(ms);
  }

  // I/O thread.
  void listen();
  void accept();
  bool host_allowed(std::string_view host) const {
    return allowed_hosts.empty() || allowed_hosts.count(std::string(host)) > 0;
  }
  // The part of `target` after "/<token>/", or nullopt when the target is not under the token.
  std::optional<std::string_view> under_token(std::string_view target) const {
    const size_t query = target.find('?');
    if (query != std::string_view::npos) target = target.substr(0, query);
    if (target.size() < token.size() + 2 || target[0] != '/' || target[token.size() + 1] != '/') return std::nullopt;
    if (!same_secret(target.substr(1, token.size()), token)) return std::nullopt;
    return target.substr(token.size() + 2);
  }
  void open_socket(tcp::socket socket, http::request<http::string_body> request);
  void socket_closed(uint64_t id);

  // Simulation thread.
  void simulate();
};

// ---------------------------------------------------------------------------------------------------
// A WebSocket: the page's messages go to the simulation's inbox; its writes are text messages in
// order, then the newest frame.

class LiveServer::Impl::Socket : public std::enable_shared_from_this<Socket> {
 public:
  Socket(Impl& server, uint64_t id, tcp::socket socket) : server_(server), id_(id), ws_(std::move(socket)) {}

  void start(http::request<http::string_body> request) {
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.set_option(websocket::stream_base::decorator(
        [](websocket::response_type& r) { r.set(http::field::server, std::string("ctsurg-live ") + kVersion); }));
    ws_.read_message_max(LiveServer::kMaxSocketMessageBytes);
    ws_.async_accept(request, [self = shared_from_this()](beast::error_code ec) { self->accepted(ec); });
  }

  void send_text(std::string text) {
    if (closing_) return;
    texts_.push_back(std::move(text));
    pump();
  }
  void send_frame(LiveFrame frame, Input input) {
    if (closing_) return;
    supersede(frame_, std::move(frame));
    if (!frame_input_ || (input && *input < *frame_input_)) frame_input_ = input;
    pump();
  }
  // Says why in a last text message, then closes.
  void close_with(const std::string& why) {
    send_text(json{{"type", "closed"}, {"message", why}}.dump());
    closing_ = true;
    pump();
  }
  void drop() {
    beast::error_code ignored;
    beast::get_lowest_layer(ws_).socket().close(ignored);
  }

 private:
  void accepted(beast::error_code ec) {
    if (ec) {
      server_.say("live: a WebSocket handshake failed: " + ec.message());
      return;
    }
    server_.sockets[id_] = weak_from_this();
    if (server_.controller != 0) {
      if (const auto old = server_.sockets[server_.controller].lock()) {
        old->close_with("another browser opened this session and now controls it; this page is disconnected "
                        "(reload it to take the session back)");
      }
      ++server_.sockets_taken_over;
      server_.say("live: a second browser took the session over; the first one was disconnected");
    }
    server_.controller = id_;
    ++server_.sockets_opened;
    server_.push({Inbound::Kind::opened, id_, {}});
    read();
  }

  void read() {
    ws_.async_read(buffer_, [self = shared_from_this()](beast::error_code ec, size_t) { self->received(ec); });
  }

  void received(beast::error_code ec) {
    if (ec) {
      if (ec == websocket::error::message_too_big) {
        server_.say("live: a socket message over " + std::to_string(LiveServer::kMaxSocketMessageBytes) +
                    " bytes: the socket was closed (1009)");
        ++server_.refused_messages;
      }
      server_.socket_closed(id_);
      return;
    }
    ++server_.messages;
    std::string text = beast::buffers_to_string(buffer_.data());
    buffer_.consume(buffer_.size());
    if (closing_ || server_.controller != id_) {
      // Taken over: what it still sends is not applied.
    } else if (!ws_.got_text()) {
      ++server_.refused_messages;
      send_text(json{{"type", "error"}, {"message", "(binary): the server takes JSON text messages only"}}.dump());
    } else if (!server_.push({Inbound::Kind::message, id_, std::move(text)})) {
      ++server_.refused_messages;
      send_text(json{{"type", "error"},
                     {"message", "(queue): over " + std::to_string(LiveServer::kMaxQueuedMessages) +
                                     " messages wait for the simulation: this one was dropped"}}
                    .dump());
    }
    read();
  }

  void pump() {
    if (writing_) return;
    if (!texts_.empty()) {
      out_text_ = std::move(texts_.front());
      texts_.pop_front();
      ws_.text(true);
      write(asio::buffer(out_text_), false);
    } else if (frame_ && !closing_) {
      out_frame_ = encode_live_frame(*frame_);
      out_input_ = frame_input_;
      frame_.reset();
      frame_input_.reset();
      ws_.binary(true);
      write(asio::buffer(out_frame_), true);
    } else if (closing_ && !closed_) {
      closed_ = true;
      writing_ = true;
      ws_.async_close(websocket::close_code::policy_error, [self = shared_from_this()](beast::error_code) {
        self->writing_ = false;
        self->drop();
      });
    }
  }

  void write(asio::const_buffer bytes, bool frame) {
    writing_ = true;
    ws_.async_write(bytes, [self = shared_from_this(), frame](beast::error_code ec, size_t n) {
      self->writing_ = false;
      if (ec) return;  // the read side reports the closed socket
      if (frame) {
        ++self->server_.frames_sent;
        self->server_.frame_bytes_sent += n;
        if (self->out_input_) self->server_.picture_written(*self->out_input_);
      }
      self->pump();
    });
  }

  Impl& server_;
  uint64_t id_;
  websocket::stream<beast::tcp_stream> ws_;
  beast::flat_buffer buffer_;
  std::deque<std::string> texts_;
  std::optional<LiveFrame> frame_;
  Input frame_input_, out_input_;
  std::string out_text_;
  std::vector<uint8_t> out_frame_;
  bool writing_ = false, closing_ = false, closed_ = false;
};

void LiveServer::Impl::send_text(uint64_t id, std::string text) {
  asio::post(io, [this, id, text = std::move(text)]() mutable {
    const auto it = sockets.find(id);
    if (it == sockets.end()) return;
    if (const auto socket = it->second.lock()) socket->send_text(std::move(text));
  });
}

void LiveServer::Impl::send_frame(uint64_t id, LiveFrame frame, Input input) {
  asio::post(io, [this, id, frame = std::move(frame), input]() mutable {
    const auto it = sockets.find(id);
    if (it == sockets.end()) return;
    if (const auto socket = it->second.lock()) socket->send_frame(std::move(frame), input);
  });
}

void LiveServer::Impl::socket_closed(uint64_t id) {
  sockets.erase(id);
  if (controller == id) {
    controller = 0;
    say("live: the browser closed the session's page");
  }
  push({Inbound::Kind::closed, id, {}});
}

// ---------------------------------------------------------------------------------------------------
// HTTP: the page's files under /<token>/, and the WebSocket's upgrade request.

class LiveServer::Impl::HttpConnection : public std::enable_shared_from_this<HttpConnection> {
 public:
  HttpConnection(Impl& server, tcp::socket socket) : server_(server), stream_(std::move(socket)) {}

  void read() {
    parser_.emplace();
    parser_->header_limit(8 * 1024);
    parser_->body_limit(4 * 1024);
    stream_.expires_after(std::chrono::seconds(30));
    http::async_read(stream_, buffer_, *parser_,
                     [self = shared_from_this()](beast::error_code ec, size_t) { self->request_read(ec); });
  }

 private:
  using Response = http::response<http::string_body>;

  void request_read(beast::error_code ec) {
    if (ec == http::error::end_of_stream || ec == beast::error::timeout) {
      stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
      return;
    }
    if (ec) {  // a malformed or oversized request: answered, then closed
      ++server_.refused_requests;
      auto r = std::make_shared<Response>(http::status::bad_request, 11);
      r->set(http::field::content_type, "text/plain; charset=utf-8");
      r->body() = "Bad request: " + ec.message() + "\n";
      r->keep_alive(false);
      r->prepare_payload();
      send(r);
      return;
    }
    ++server_.http_requests;
    http::request<http::string_body> request = parser_->release();
    if (websocket::is_upgrade(request)) {
      const std::string refusal = socket_refusal(request);
      if (refusal.empty()) {
        server_.open_socket(stream_.release_socket(), std::move(request));
        return;
      }
      ++server_.refused_requests;
      server_.say("live: a WebSocket was refused: " + refusal);
      send(plain(request, http::status::forbidden, refusal));
      return;
    }
    send(answer(request));
  }

  // Empty when the upgrade request may open the session's socket, else why not.
  std::string socket_refusal(const http::request<http::string_body>& request) const {
    const std::string_view host = view(request[http::field::host]);
    if (!server_.host_allowed(host)) return "the Host header (" + std::string(host.substr(0, 100)) + ") is not this server";
    const auto path = server_.under_token(view(request.target()));
    if (!path || *path != "ws") return "the socket's URL does not carry this session's token";
    const std::string_view origin = view(request[http::field::origin]);
    if (origin != "http://" + std::string(host)) {
      return "the Origin (" + std::string(origin.substr(0, 100)) + ") is not this server's page";
    }
    return {};
  }

  std::shared_ptr<Response> plain(const http::request<http::string_body>& request, http::status status,
                                  const std::string& text) const {
    auto r = std::make_shared<Response>(status, request.version());
    r->set(http::field::content_type, "text/plain; charset=utf-8");
    r->set(http::field::cache_control, "no-store");
    r->body() = text + "\n";
    r->keep_alive(request.keep_alive());
    r->prepare_payload();
    return r;
  }

  std::shared_ptr<Response> answer(const http::request<http::string_body>& request) const {
    if (!server_.host_allowed(view(request[http::field::host]))) {
      ++server_.refused_requests;
      return plain(request, http::status::misdirected_request, "This server does not answer to that host name.");
    }
    if (request.method() != http::verb::get && request.method() != http::verb::head) {
      ++server_.refused_requests;
      auto r = plain(request, http::status::method_not_allowed, "Only GET and HEAD.");
      r->set(http::field::allow, "GET, HEAD");
      return r;
    }
    const auto path = server_.under_token(view(request.target()));
    if (!path) {
      // Also a URL with the token but without its final slash: the page's relative URLs need it.
      ++server_.refused_requests;
      return plain(request, http::status::not_found,
                   "Not found. A ctsurg-live session opens only at the full URL it printed, token included.");
    }
    std::string body, type;
    if (*path == "uvs.bin" && !server_.options.uvs.empty()) {
      body.assign(reinterpret_cast<const char*>(server_.options.uvs.data()), 4 * server_.options.uvs.size());
      type = "application/octet-stream";
    } else if (*path == "normal_map.bin" && !server_.options.normal_map_rgba.empty()) {
      body.assign(server_.options.normal_map_rgba.begin(), server_.options.normal_map_rgba.end());
      type = "application/octet-stream";
    } else {
      for (const live_page::Asset& asset : live_page::assets()) {
        if (asset.name == *path) {
          body.assign(reinterpret_cast<const char*>(asset.bytes.data()), asset.bytes.size());
          type = asset.content_type;
        }
      }
      if (type.empty()) {
        ++server_.refused_requests;
        return plain(request, http::status::not_found, "Not found.");
      }
    }
    auto r = std::make_shared<Response>(http::status::ok, request.version());
    r->set(http::field::server, std::string("ctsurg-live ") + kVersion);
    r->set(http::field::content_type, type);
    r->set(http::field::cache_control, "no-store");
    r->set("X-Content-Type-Options", "nosniff");
    r->set("X-Frame-Options", "DENY");
    r->set("Referrer-Policy", "no-referrer");  // the token stays in this origin
    r->set("Content-Security-Policy",
           "default-src 'self'; script-src 'self'; style-src 'self'; img-src 'self' blob: data:; connect-src 'self'; "
           "base-uri 'none'; form-action 'none'; frame-ancestors 'none'");
    r->keep_alive(request.keep_alive());
    if (request.method() == http::verb::head) {
      r->content_length(body.size());
    } else {
      r->body() = std::move(body);
      r->prepare_payload();
    }
    return r;
  }

  void send(std::shared_ptr<Response> r) {
    http::async_write(stream_, *r, [self = shared_from_this(), r](beast::error_code ec, size_t) {
      if (ec) return;
      if (r->keep_alive()) {
        self->read();
      } else {
        self->stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
      }
    });
  }

  Impl& server_;
  beast::tcp_stream stream_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
};

void LiveServer::Impl::open_socket(tcp::socket socket, http::request<http::string_body> request) {
  std::make_shared<Socket>(*this, next_socket++, std::move(socket))->start(std::move(request));
}

void LiveServer::Impl::listen() {
  beast::error_code ec;
  const asio::ip::address address = asio::ip::make_address(options.host, ec);
  if (ec) throw InputError(options.host, "--host", "not a numeric IPv4 or IPv6 address (" + ec.message() + ")");
  const tcp::endpoint endpoint(address, options.port);
  acceptor.open(endpoint.protocol(), ec);
  if (!ec) acceptor.set_option(asio::socket_base::reuse_address(true), ec);
  if (!ec) acceptor.bind(endpoint, ec);
  if (!ec) acceptor.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) {
    throw InputError(host_text(address, options.port), "--port", "cannot listen there: " + ec.message());
  }
  port = acceptor.local_endpoint().port();
  if (!address.is_unspecified()) {
    allowed_hosts.insert(host_text(address, port));
    if (address.is_loopback()) allowed_hosts.insert("localhost:" + std::to_string(port));
  }
  const std::string shown = address.is_unspecified() ? (address.is_v6() ? "[::1]" : "127.0.0.1") : "";
  url = "http://" + (shown.empty() ? host_text(address, port) : shown + ":" + std::to_string(port)) + "/" + token + "/";
}

void LiveServer::Impl::accept() {
  acceptor.async_accept([this](beast::error_code ec, tcp::socket socket) {
    if (ec) {
      if (ec != asio::error::operation_aborted) say("live: accept failed: " + ec.message());
    } else {
      std::make_shared<HttpConnection>(*this, std::move(socket))->read();
    }
    if (!stopping) accept();
  });
}

// ---------------------------------------------------------------------------------------------------
// The simulation thread: the page's messages at step boundaries, one picture per tick.

void LiveServer::Impl::simulate() {
  const auto tick = std::chrono::duration<double>(1.0 / options.picture_hz);
  LiveProtocolLimits limits;
  limits.bounds = session.rest_bounds();
  limits.margin_mm = options.margin_mm;

  uint64_t current = 0;          // the socket that controls the session (0: none)
  uint64_t sent_topology = 0;    // the topology of the last frame sent to it
  uint64_t frame_number = 0;
  uint32_t last_seq = 0;         // the last message's seq handed to the session
  std::map<int, uint64_t> tools; // user tools not ended -> the socket that began them
  bool paused_by_leaving = false;
  Input input;                   // the oldest message handled since the last frame
  uint16_t last_flags = 0;
  LiveClock clock(tick.count(), options.realtime_factor);
  int last_halvings = session.halvings();
  // The status line: real-time factor and pictures over the last ~second.
  auto window_start = Clock::now();
  double window_sim = 0;
  uint64_t window_frames = frames_sent.load();
  double rtf = 0, pictures_per_s = 0;
  auto last_status = Clock::now() - std::chrono::seconds(1);
  size_t last_frame_bytes = 0;

  const auto error = [&](const std::string& message, const LiveMessage* m) {
    ++refused_messages;
    json e{{"type", "error"}, {"message", message}};
    if (m && m->has_seq) e["seq"] = m->seq;
    send_text(current, e.dump());
  };
  const auto end_tools = [&](uint64_t owner, const std::string& why, bool tell) {
    for (auto it = tools.begin(); it != tools.end();) {
      if (owner != 0 && it->second != owner) {
        ++it;
        continue;
      }
      if (session.tool_active(it->first)) session.end_tool(it->first);
      if (tell) send_text(current, json{{"type", "ended"}, {"id", it->first}, {"why", why}}.dump());
      it = tools.erase(it);
    }
  };
  const auto hello = [&]() {
    const std::array<double, 6> b = session.rest_bounds();
    std::vector<float> lps;
    session.surface(lps);
    json h{{"type", "hello"},
           {"scenario", session.scenario().name},
           {"model", options.model_description},
           {"vertex_count", lps.size() / 3},
           {"triangle_count", session.triangles().size() / 3},
           {"bounds", b},
           {"margin_mm", options.margin_mm},
           {"dt_s", session.dt()},
           {"colour", options.colour},
           {"uvs", !options.uvs.empty()},
           {"normal_map", nullptr},
           {"tools",
            {{"grab_radius_mm", options.grab_radius_mm},
             {"probe_radius_mm", options.probe_radius_mm},
             {"cut_depth_mm", options.cut_depth_mm}}},
           {"save_to", nullptr},
           {"library", std::string(live_page::library())},
           {"version", std::string("ctsurg ") + kVersion}};
    if (!options.normal_map_rgba.empty()) {
      h["normal_map"] = {{"width", options.normal_map_width}, {"height", options.normal_map_height}};
    }
    if (!options.save_scenario.empty()) {
      h["save_to"] = {{"scenario", options.save_scenario.string()}, {"trajectory", options.save_trajectory.string()}};
    }
    send_text(current, h.dump());
  };

  const auto handle = [&](const LiveMessage& m) {
    switch (m.type) {
      case LiveMessage::Type::begin: {
        const int id = session.begin_tool(live_tool_spec(m));
        tools[id] = current;
        unsaved = true;
        json b{{"type", "began"}, {"id", id}};
        if (m.has_seq) b["seq"] = m.seq;
        send_text(current, b.dump());
        break;
      }
      case LiveMessage::Type::move:
        if (!tools.count(m.id)) throw InputError("message", "id", std::to_string(m.id) + " is not a tool this page holds");
        session.move_tool(m.id, m.position_mm);
        unsaved = true;
        break;
      case LiveMessage::Type::end:
        if (!tools.count(m.id)) throw InputError("message", "id", std::to_string(m.id) + " is not a tool this page holds");
        session.end_tool(m.id);
        tools.erase(m.id);
        unsaved = true;
        break;
      case LiveMessage::Type::pause:
        session.pause();
        break;
      case LiveMessage::Type::resume:
        session.resume();
        break;
      case LiveMessage::Type::reset:
        end_tools(0, "the session was reset", true);
        session.reset();
        unsaved = true;
        last_halvings = session.halvings();
        break;
      case LiveMessage::Type::save: {
        if (options.save_scenario.empty()) {
          throw InputError("message", "save", "this session was started without --save: it cannot write files");
        }
        session.save(options.save_scenario, options.save_trajectory);
        unsaved = false;
        ++saves;
        say("live: saved " + options.save_scenario.string() + " and " + options.save_trajectory.string() + " (" +
            std::to_string(session.frames()) + " frames, " + std::to_string(session.time()) + " s)");
        json s{{"type", "saved"},
               {"scenario", options.save_scenario.string()},
               {"trajectory", options.save_trajectory.string()},
               {"frames", session.frames()},
               {"time_s", session.time()}};
        if (m.has_seq) s["seq"] = m.seq;
        send_text(current, s.dump());
        break;
      }
    }
  };

  while (!stopping) {
    const auto tick_start = Clock::now();
    for (Inbound& in : take_inbox()) {
      if (in.kind == Inbound::Kind::opened) {
        // A browser took the session (over): its predecessor's tools end as if it had let go.
        end_tools(0, "another browser took the session over", false);
        current = in.socket;
        sent_topology = 0;
        hello();
        if (paused_by_leaving) {
          session.resume();
          paused_by_leaving = false;
        }
      } else if (in.kind == Inbound::Kind::closed) {
        if (in.socket != current) continue;
        // The page went away (closed mid-drag, perhaps): its tools are let go, the session pauses
        // once that is applied, and the recording so far is kept.
        end_tools(in.socket, "", false);
        current = 0;
        if (!session.paused()) {
          session.advance_events(1);
          session.pause();
          paused_by_leaving = true;
        }
      } else if (in.socket == current) {
        LiveMessage m;
        if (!input) input = in.received;
        try {
          m = parse_live_message(in.text, limits);
          if (m.has_seq) last_seq = m.seq;
          handle(m);
        } catch (const InputError& e) {
          error(e.what(), &m);
        }
      }
    }

    double advanced = 0, advance_wall = 0;
    if (clock.owed(session.paused())) {
      const LiveAdvance a = session.advance(clock.budget_s(), clock.advance_factor());
      advanced = a.sim_s;
      advance_wall = a.wall_s;
      clock.advanced(a.sim_s);
      if (session.halvings() != last_halvings) {
        last_halvings = session.halvings();
        send_text(current, json{{"type", "guard"}, {"action", "halved"}, {"message", session.restart_message()}}.dump());
        say("live: " + session.restart_message());
      }
      if (a.stopped) {
        end_tools(0, "the session stopped: " + session.stopped_message(), true);
        send_text(current, json{{"type", "guard"}, {"action", "stopped"}, {"message", session.stopped_message()}}.dump());
        say("live: " + session.stopped_message());
      }
    }
    window_sim += advanced;

    // A picture when something changed (a quasi-static model skips ticks; a paused one stands still;
    // the page's messages show in the next picture that advanced).
    const uint16_t flags = (session.paused() ? LiveFrame::paused : 0) | (session.stopped_message().empty() ? 0 : LiveFrame::stopped);
    if (current != 0 && (advanced > 0 || sent_topology != session.topology_version() || flags != last_flags)) {
      LiveFrame f = live_frame_of(session, frame_number++, sent_topology);
      f.seq = last_seq;
      sent_topology = f.topology_version;
      last_flags = flags;
      last_frame_bytes = LiveFrame::kHeaderBytes + 4 * (f.positions.size() + f.triangles.size());
      send_frame(current, std::move(f), input);
      input.reset();
    }

    const auto now = Clock::now();
    const double window = std::chrono::duration<double>(now - window_start).count();
    if (window >= 1.0) {
      rtf = window_sim / window;
      pictures_per_s = static_cast<double>(frames_sent.load() - window_frames) / window;
      window_start = now;
      window_sim = 0;
      window_frames = frames_sent.load();
    }
    if (current != 0 && now - last_status >= std::chrono::milliseconds(250)) {
      last_status = now;
      send_text(current, json{{"type", "status"},
                              {"time_s", session.time()},
                              {"steps", session.steps()},
                              {"dt_s", session.dt()},
                              {"rtf", rtf},
                              {"pictures_per_s", pictures_per_s},
                              {"paused", session.paused()},
                              {"stopped", session.stopped_message()},
                              {"halvings", session.halvings()},
                              {"frames_recorded", session.frames()},
                              {"frame_bytes", last_frame_bytes}}
                             .dump());
    }
    clock.tick_done(std::chrono::duration<double>(Clock::now() - tick_start).count(), advance_wall);
    // The rest of the tick, if the physics left any (it takes the whole tick when it is behind).
    std::this_thread::sleep_until(tick_start + std::chrono::duration_cast<Clock::duration>(tick));
  }
}

// ---------------------------------------------------------------------------------------------------

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
  impl_->token = o.token.empty() ? random_token() : o.token;
  if (impl_->token.size() < 16 || impl_->token.find_first_not_of("0123456789abcdefghijklmnopqrstuvwxyz") != std::string::npos) {
    throw InputError("live server", "token", "at least 16 characters, lowercase letters and digits only");
  }
  impl_->listen();
  if (o.stop_on_signals) {
    impl_->signals.emplace(impl_->io, SIGINT, SIGTERM);
    impl_->signals->async_wait([this](beast::error_code ec, int) {
      if (!ec) stop();
    });
  }
}

LiveServer::~LiveServer() { stop(); }

std::string LiveServer::url() const { return impl_->url; }
uint16_t LiveServer::port() const { return impl_->port; }
const std::string& LiveServer::token() const { return impl_->token; }
bool LiveServer::unsaved() const { return impl_->unsaved; }

LiveServerStats LiveServer::stats() const {
  const Impl& i = *impl_;
  LiveServerStats st{i.frames_sent, i.frame_bytes_sent, i.messages, i.refused_messages, i.http_requests,
                     i.refused_requests, i.sockets_opened, i.sockets_taken_over, i.saves, {}};
  std::lock_guard lock(impl_->latency_mutex);
  st.input_to_picture_ms = impl_->latencies_ms;
  return st;
}

void LiveServer::run() {
  Impl& i = *impl_;
  i.accept();
  std::thread simulation([&i] {
    try {
      i.simulate();
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
