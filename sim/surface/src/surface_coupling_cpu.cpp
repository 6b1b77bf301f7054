// The CPU build of the surface coupling kernel (surface_coupling_impl.h): OpenMP over vertices.
#include "ctsurg/sim/base/parallel.h"
#include "ctsurg/sim/surface/kernels/surface_coupling_impl.h"
#include "surface_cpu_kernels.h"

#include <omp.h>

namespace ctsurg::sim::cpu {

void move_surface(const SurfaceCouplingView& view, int threads) {
  const int t = thread_count(threads, view.count);
#pragma omp parallel for schedule(static) num_threads(t)
  for (int64_t i = 0; i < view.count; ++i) move_vertex(view, i);
}

}  // namespace ctsurg::sim::cpu
