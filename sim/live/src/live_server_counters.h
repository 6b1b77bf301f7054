// ctsurg-live's counters, shared by its threads: the HTTP connections and sockets (networking thread)
// and the session pump (simulation thread) count into them; LiveServer::stats() reads them from any
// thread.
#pragma once

#include "ctsurg/sim/live/live_server.h"
#include "live_inbox.h"

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <vector>

namespace ctsurg::sim {

struct LiveServerCounters {
  std::atomic<uint64_t> frames_sent{0}, frame_bytes_sent{0}, messages{0}, refused_messages{0}, http_requests{0},
      refused_requests{0}, sockets_opened{0}, sockets_taken_over{0}, saves{0};

  // Networking thread: a frame answering a page message that arrived at `input` was written. The last
  // 50,000 to 100,000 are kept.
  void picture_written(LiveWallClock::time_point input) {
    const double ms = std::chrono::duration<double, std::milli>(LiveWallClock::now() - input).count();
    std::lock_guard lock(latency_mutex_);
    if (latencies_ms_.size() >= 100000) latencies_ms_.erase(latencies_ms_.begin(), latencies_ms_.begin() + 50000);
    latencies_ms_.push_back(ms);
  }

  LiveServerStats stats() const {
    LiveServerStats st{frames_sent, frame_bytes_sent, messages, refused_messages, http_requests,
                       refused_requests, sockets_opened, sockets_taken_over, saves, {}};
    std::lock_guard lock(latency_mutex_);
    st.input_to_picture_ms = latencies_ms_;
    return st;
  }

 private:
  mutable std::mutex latency_mutex_;
  std::vector<double> latencies_ms_;
};

}  // namespace ctsurg::sim
