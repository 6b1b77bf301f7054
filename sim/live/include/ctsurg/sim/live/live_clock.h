// Real-time pacing of a live session, shared by ctsurg-live's simulation thread and the live benchmark
// (bench/bench_live_session.cpp), so the benchmark measures what the server does.
//
// The session is owed realtime_factor simulated seconds per wall second (measured between ticks, so a
// late tick owes its lateness too; ticks are 1/picture rate of wall time apart). What a late tick (a refactorisation, a busy machine) leaves owed is caught up in the next ticks, up
// to kMaxBacklogS of simulated time; beyond that the backlog is dropped, so a model slower than real
// time runs as fast as it can (the real-time factor it reaches is what the status reports) and never
// rushes to catch up. An event that ran ahead (a quasi-static frame longer than a tick) is paid back
// by ticks that do not advance. The wall time a tick gives LiveSession::advance is the tick less what
// the rest of the last tick took (messages, the frame), so a tick's work fits in its tick, but at
// least a quarter of the tick.
#pragma once

#include <algorithm>
#include <chrono>

namespace ctsurg::sim {

class LiveClock {
 public:
  static constexpr double kMaxBacklogS = 0.1;  // simulated s a late tick may leave owed

  LiveClock(double tick_s, double realtime_factor) : tick_s_(tick_s), factor_(realtime_factor) {}

  // At a tick's start: whether the session is owed simulated time this tick (a paused one never is,
  // and owes nothing when it resumes).
  bool owed(bool paused) {
    const auto now = std::chrono::steady_clock::now();
    const double elapsed = started_ ? std::chrono::duration<double>(now - last_).count() : tick_s_;
    started_ = true;
    last_ = now;
    owed_s_ = paused ? 0 : std::min(owed_s_ + elapsed * factor_, std::max(tick_s_, kMaxBacklogS) * factor_);
    return owed_s_ > 0;
  }
  // This tick's LiveSession::advance(budget_s(), advance_factor()): at most budget_s() of wall time,
  // for the simulated time owed.
  double budget_s() const { return std::max(0.25 * tick_s_, tick_s_ - overhead_s_); }
  double advance_factor() const { return owed_s_ / budget_s(); }
  // After LiveSession::advance: the simulated seconds it advanced.
  void advanced(double sim_s) { owed_s_ -= sim_s; }
  // At the tick's end: the wall seconds of the tick's work, and of advance's part of it.
  void tick_done(double work_s, double advance_s) { overhead_s_ = std::max(0.0, work_s - advance_s); }

 private:
  double tick_s_, factor_;
  double owed_s_ = 0;      // simulated seconds owed to real time
  bool started_ = false;
  std::chrono::steady_clock::time_point last_;  // the last tick's start
  double overhead_s_ = 0;  // the last tick's work besides advancing
};

}  // namespace ctsurg::sim
