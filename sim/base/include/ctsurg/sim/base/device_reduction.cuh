// Deterministic sums of doubles on a CUDA device (nvcc only): the same bits on every run, whatever the
// scheduling, because no atomics take part and every addition happens in a fixed order.
//
//   1. each block of a one-thread-per-index kernel sums its threads' values with block_sum (a tree over
//      shared memory: thread t adds t + s for s = kThreads/2, ..., 1) and writes one partial per block;
//   2. a kernel of a single block adds the partials with sum_in_one_block: thread t adds partials t,
//      t + kThreads, t + 2 kThreads, ... in order, then block_sum.
//
// The order differs from a serial host loop, so a device sum and a host sum of the same values agree
// to rounding (a relative 1e-15 or so), not bit for bit.
#pragma once

#include <cstdint>

namespace ctsurg::sim::cuda {

// The sum of v over the kThreads threads of the block (a power of two, == blockDim.x); every thread of
// the block must call it (it synchronises). Returns the sum in thread 0 and 0 in the others (only
// thread 0 reads shared[0], so two calls in a row on the same shared array do not race).
// shared: kThreads doubles.
template <int kThreads>
__device__ inline double block_sum(double v, double* shared) {
  static_assert(kThreads > 0 && (kThreads & (kThreads - 1)) == 0, "a power of two");
  shared[threadIdx.x] = v;
  __syncthreads();
#pragma unroll
  for (int s = kThreads / 2; s > 0; s /= 2) {
    if (static_cast<int>(threadIdx.x) < s) shared[threadIdx.x] += shared[threadIdx.x + s];
    __syncthreads();
  }
  return threadIdx.x == 0 ? shared[0] : 0.0;
}

// The sum of partials[0 .. count) by one block of kThreads threads (== blockDim.x), in the fixed order
// described above; every thread must call it; the sum in thread 0, 0 in the others. shared: kThreads
// doubles.
template <int kThreads>
__device__ inline double sum_in_one_block(const double* partials, int64_t count, double* shared) {
  double v = 0;
  for (int64_t k = threadIdx.x; k < count; k += kThreads) v += partials[k];
  return block_sum<kThreads>(v, shared);
}

}  // namespace ctsurg::sim::cuda
