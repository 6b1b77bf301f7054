// The CPU build of the cutting kernels (spring_cutting_impl.h): OpenMP over particles or springs.
#include "ctsurg/sim/springs/kernels/spring_cutting_impl.h"
#include "spring_cpu_kernels.h"

#include <omp.h>

namespace ctsurg::sim::cpu {

int64_t cut_grid(const SpringGridView& grid, uint32_t* spring_mask, const Real* x, const Real* y, const Real* z,
                 const TriangleView& blade, int threads) {
  const int t = thread_count(threads, grid.count);
  int64_t cleared = 0;
#pragma omp parallel for schedule(static) num_threads(t) reduction(+ : cleared)
  for (int32_t i = 0; i < grid.count; ++i) {
    const uint32_t before = spring_mask[i];
    const uint32_t after = grid_mask_after_cut(grid, x, y, z, blade, i);
    spring_mask[i] = after;  // the kernel read only particle i's own mask
    cleared += __builtin_popcount(before & ~after);
  }
  return cleared;
}

int64_t cut_explicit(const int32_t* ends, uint8_t* alive, int32_t springs, const Real* x, const Real* y, const Real* z,
                     const TriangleView& blade, int threads) {
  const int t = thread_count(threads, springs);
  int64_t cut = 0;
#pragma omp parallel for schedule(static) num_threads(t) reduction(+ : cut)
  for (int32_t s = 0; s < springs; ++s) {
    const uint8_t after = explicit_alive_after_cut(ends, alive, x, y, z, blade, s);
    cut += alive[s] != after;
    alive[s] = after;
  }
  return cut;
}

}  // namespace ctsurg::sim::cpu
