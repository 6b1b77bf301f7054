// A progress bar for long work, drawn on stderr only when stderr is a terminal (never in logs or
// pipes) and CTSURG_NO_PROGRESS is unset. advance() is thread-safe and cheap; redraws are throttled.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

namespace ctsurg {

class ProgressBar {
 public:
  ProgressBar(std::string label, uint64_t total);
  ~ProgressBar();  // finishes the line
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  void advance(uint64_t n = 1);
  bool enabled() const { return enabled_; }
  static bool terminal_attached();
  // Tools call this once with --quiet so no bar is drawn.
  static void set_globally_enabled(bool on);

 private:
  void draw(uint64_t done, bool final);
  std::string label_;
  uint64_t total_;
  std::atomic<uint64_t> done_{0};
  bool enabled_;
  std::mutex draw_mutex_;
  std::chrono::steady_clock::time_point start_, last_draw_;
};

}  // namespace ctsurg
