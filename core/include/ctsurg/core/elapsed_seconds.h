// Wall-clock time since a steady-clock instant, in seconds: what the solvers' and meshers' reports and
// logs give as their phase times.
#pragma once

#include <chrono>

namespace ctsurg {

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace ctsurg
