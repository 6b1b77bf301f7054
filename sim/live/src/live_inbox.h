// ctsurg-live's inbox: what the networking thread hands the simulation thread (live_session_pump.h), in
// arrival order. A socket opened or closed always gets in; a page's message only while fewer than
// max_messages wait (beyond that the socket answers "busy", live_websocket.cpp).
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <string>
#include <utility>

namespace ctsurg::sim {

using LiveWallClock = std::chrono::steady_clock;
// When the oldest page message a frame answers arrived (nullopt: the frame answers none); the server
// times each such frame to its last byte on the socket (LiveServerStats::input_to_picture_ms).
using LiveInputTime = std::optional<LiveWallClock::time_point>;

struct LiveInbound {
  enum class Kind { opened, message, closed };
  Kind kind = Kind::message;
  uint64_t socket = 0;                     // the socket's id (live_websocket.h), from 1
  std::string text;                        // message: the page's text, unparsed
  LiveWallClock::time_point received = LiveWallClock::now();
};

class LiveInbox {
 public:
  explicit LiveInbox(size_t max_messages) : max_messages_(max_messages) {}

  // Any thread. False (and nothing queued) for a message when max_messages already wait.
  bool push(LiveInbound in) {
    std::lock_guard lock(mutex_);
    if (in.kind == LiveInbound::Kind::message && queue_.size() >= max_messages_) return false;
    queue_.push_back(std::move(in));
    return true;
  }
  // Everything waiting, oldest first; the inbox is left empty.
  std::deque<LiveInbound> take() {
    std::lock_guard lock(mutex_);
    return std::exchange(queue_, {});
  }

 private:
  size_t max_messages_;
  std::mutex mutex_;
  std::deque<LiveInbound> queue_;
};

}  // namespace ctsurg::sim
