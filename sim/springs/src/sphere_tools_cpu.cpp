// The CPU build of the spherical tool kernels (sphere_tools_impl.h): OpenMP over particles.
#include "ctsurg/sim/springs/kernels/sphere_tools_impl.h"
#include "spring_cpu_kernels.h"

#include <omp.h>

namespace ctsurg::sim::cpu {

void grabbable(const Real* x, const Real* y, const Real* z, const Real* inv_mass, int32_t count, const SphereView& tool,
               uint8_t* inside, int threads) {
  const int t = thread_count(threads, count);
#pragma omp parallel for schedule(static) num_threads(t)
  for (int32_t i = 0; i < count; ++i) inside[i] = ctsurg::sim::grabbable(x, y, z, inv_mass, tool, i) ? 1 : 0;
}

int64_t probe(Real* x, Real* y, Real* z, const Real* inv_mass, int32_t count, const SphereView& tool, int threads) {
  const int t = thread_count(threads, count);
  int64_t moved = 0;
#pragma omp parallel for schedule(static) num_threads(t) reduction(+ : moved)
  for (int32_t i = 0; i < count; ++i) moved += probe_particle(x, y, z, inv_mass, tool, i);
  return moved;
}

void place_grabbed(Real* x, Real* y, Real* z, const int32_t* ids, const Real* offsets, int64_t count,
                   const SphereView& tool, int threads) {
  const int t = thread_count(threads, count);
#pragma omp parallel for schedule(static) num_threads(t)
  for (int64_t g = 0; g < count; ++g) ctsurg::sim::place_grabbed(x, y, z, ids, offsets, tool, g);
}

}  // namespace ctsurg::sim::cpu
