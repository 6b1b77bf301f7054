// The CPU build of the instrument contact kernel (base/kernels/instrument_contact_impl.h): OpenMP over particles.
#include "ctsurg/sim/base/kernels/instrument_contact_impl.h"
#include "spring_cpu_kernels.h"

#include <omp.h>

namespace ctsurg::sim::cpu {

int64_t push_out(Real* x, Real* y, Real* z, const Real* inv_mass, int32_t count, const InstrumentView& view, int threads) {
  const int t = thread_count(threads, count);
  int64_t moved = 0;
#pragma omp parallel for schedule(static) num_threads(t) reduction(+ : moved)
  for (int32_t i = 0; i < count; ++i) {
    if (inv_mass[i] != Real(0)) moved += push_out_of_instrument(view, &x[i], &y[i], &z[i]);
  }
  return moved;
}

}  // namespace ctsurg::sim::cpu
