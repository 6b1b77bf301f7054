#include "ctsurg/core/progress_bar.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>

namespace ctsurg {

namespace {
std::atomic<bool> g_enabled{true};
}

bool ProgressBar::terminal_attached() {
  return ::isatty(STDERR_FILENO) == 1 && std::getenv("CTSURG_NO_PROGRESS") == nullptr;
}

void ProgressBar::set_globally_enabled(bool on) { g_enabled = on; }

ProgressBar::ProgressBar(std::string label, uint64_t total)
    : label_(std::move(label)), total_(total), enabled_(g_enabled && total > 0 && terminal_attached()) {
  start_ = last_draw_ = std::chrono::steady_clock::now();
  if (enabled_) draw(0, false);
}

ProgressBar::~ProgressBar() {
  if (enabled_) draw(done_.load(), true);
}

void ProgressBar::advance(uint64_t n) {
  const uint64_t done = done_.fetch_add(n) + n;
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_draw_ < std::chrono::milliseconds(100)) return;
  std::unique_lock lock(draw_mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return;
  last_draw_ = now;
  draw(done, false);
}

void ProgressBar::draw(uint64_t done, bool final) {
  if (done > total_) done = total_;
  const double f = total_ ? double(done) / double(total_) : 1.0;
  constexpr int kWidth = 30;
  const int filled = static_cast<int>(f * kWidth);
  char bar[kWidth + 1];
  for (int i = 0; i < kWidth; ++i) bar[i] = i < filled ? '#' : '.';
  bar[kWidth] = 0;
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::fprintf(stderr, "\r%-24s [%s] %3d%% %6.1fs%s", label_.c_str(), bar, static_cast<int>(f * 100.0), elapsed,
               final ? "\n" : "");
  std::fflush(stderr);
}

}  // namespace ctsurg
