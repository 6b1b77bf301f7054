// How many OpenMP threads a CPU kernel launcher uses (the *_cpu.cpp files of every sim library).
#pragma once

#include <omp.h>

#include <algorithm>
#include <cstdint>

namespace ctsurg::sim::cpu {

// OpenMP threads for a kernel over `work` items: `requested` when > 0, else one thread per 8,192 items
// up to OpenMP's default (a small kernel is shorter than waking a thread team, and much shorter when
// the cores are busy with other work).
inline int thread_count(int requested, int64_t work) {
  if (requested > 0) return requested;
  return static_cast<int>(std::clamp<int64_t>(work / 8192, 1, omp_get_max_threads()));
}

}  // namespace ctsurg::sim::cpu
