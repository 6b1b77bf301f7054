// ctsurg-live's WebSockets (live_websocket.h).
#include "live_websocket.h"

#include "ctsurg/core/version.h"
#include "ctsurg/sim/live/live_server.h"

#include <boost/asio/post.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>

#include <deque>
#include <optional>
#include <vector>

namespace ctsurg::sim {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;

namespace {

// A frame waiting for its socket: when a newer one replaces it unsent, the triangles it carried move
// to the newer one (same topology: the simulation sends the triangles only with the first frame of a
// topology), so the page never misses a topology change.
void supersede_waiting_frame(std::optional<LiveFrame>& waiting, LiveFrame next) {
  if (waiting && (waiting->flags & LiveFrame::triangles_follow) && !(next.flags & LiveFrame::triangles_follow) &&
      waiting->topology_version == next.topology_version) {
    next.triangles = std::move(waiting->triangles);
    next.flags |= LiveFrame::triangles_follow;
  }
  waiting = std::move(next);
}

}  // namespace

// One WebSocket: the page's messages go to the inbox; its writes are text messages in order, then the
// newest frame.
class LiveSocket : public std::enable_shared_from_this<LiveSocket> {
 public:
  LiveSocket(LiveSockets& sockets, uint64_t id, tcp::socket socket) : sockets_(sockets), id_(id), ws_(std::move(socket)) {}

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
  void send_frame(LiveFrame frame, LiveInputTime input) {
    if (closing_) return;
    supersede_waiting_frame(frame_, std::move(frame));
    if (!frame_input_ || (input && *input < *frame_input_)) frame_input_ = input;
    pump();
  }
  // Says why in a last text message, then closes.
  void close_with(const std::string& why) {
    send_text(encode_live_server_message(LiveClosed{why}));
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
      sockets_.log_("live: a WebSocket handshake failed: " + ec.message());
      return;
    }
    sockets_.handshake_done(id_, weak_from_this());
    read();
  }

  void read() {
    ws_.async_read(buffer_, [self = shared_from_this()](beast::error_code ec, size_t) { self->received(ec); });
  }

  void received(beast::error_code ec) {
    LiveServerCounters& counters = sockets_.counters_;
    if (ec) {
      if (ec == websocket::error::message_too_big) {
        sockets_.log_("live: a socket message over " + std::to_string(LiveServer::kMaxSocketMessageBytes) +
                      " bytes: the socket was closed (1009)");
        ++counters.refused_messages;
      }
      sockets_.closed(id_);
      return;
    }
    ++counters.messages;
    std::string text = beast::buffers_to_string(buffer_.data());
    buffer_.consume(buffer_.size());
    if (closing_ || !sockets_.controls(id_)) {
      // Taken over: what it still sends is not applied.
    } else if (!ws_.got_text()) {
      ++counters.refused_messages;
      send_text(encode_live_server_message(LiveError{"(binary): the server takes JSON text messages only", {}}));
    } else if (!sockets_.inbox_.push({LiveInbound::Kind::message, id_, std::move(text)})) {
      ++counters.refused_messages;
      send_text(encode_live_server_message(
          LiveError{"(queue): over " + std::to_string(LiveServer::kMaxQueuedMessages) +
                        " messages wait for the simulation: this one was dropped",
                    {}}));
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
        LiveServerCounters& counters = self->sockets_.counters_;
        ++counters.frames_sent;
        counters.frame_bytes_sent += n;
        if (self->out_input_) counters.picture_written(*self->out_input_);
      }
      self->pump();
    });
  }

  LiveSockets& sockets_;
  uint64_t id_;
  websocket::stream<beast::tcp_stream> ws_;
  beast::flat_buffer buffer_;
  std::deque<std::string> texts_;
  std::optional<LiveFrame> frame_;
  LiveInputTime frame_input_, out_input_;
  std::string out_text_;
  std::vector<uint8_t> out_frame_;
  bool writing_ = false, closing_ = false, closed_ = false;
};

void LiveSockets::open(tcp::socket socket, http::request<http::string_body> request) {
  std::make_shared<LiveSocket>(*this, next_socket_++, std::move(socket))->start(std::move(request));
}

void LiveSockets::handshake_done(uint64_t id, std::weak_ptr<LiveSocket> socket) {
  sockets_[id] = std::move(socket);
  if (controller_ != 0) {
    if (const auto old = sockets_[controller_].lock()) {
      old->close_with("another browser opened this session and now controls it; this page is disconnected "
                      "(reload it to take the session back)");
    }
    ++counters_.sockets_taken_over;
    log_("live: a second browser took the session over; the first one was disconnected");
  }
  controller_ = id;
  ++counters_.sockets_opened;
  inbox_.push({LiveInbound::Kind::opened, id, {}});
}

void LiveSockets::closed(uint64_t id) {
  sockets_.erase(id);
  if (controller_ == id) {
    controller_ = 0;
    log_("live: the browser closed the session's page");
  }
  inbox_.push({LiveInbound::Kind::closed, id, {}});
}

void LiveSockets::post_text(uint64_t id, std::string text) {
  asio::post(io_, [this, id, text = std::move(text)]() mutable {
    const auto it = sockets_.find(id);
    if (it == sockets_.end()) return;
    if (const auto socket = it->second.lock()) socket->send_text(std::move(text));
  });
}

void LiveSockets::post_frame(uint64_t id, LiveFrame frame, LiveInputTime input) {
  asio::post(io_, [this, id, frame = std::move(frame), input]() mutable {
    const auto it = sockets_.find(id);
    if (it == sockets_.end()) return;
    if (const auto socket = it->second.lock()) socket->send_frame(std::move(frame), input);
  });
}

}  // namespace ctsurg::sim
