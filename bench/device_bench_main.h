// main() of the CUDA device benchmarks (bench_device_simulation.cpp, bench_fem_device.cpp): without a
// device, or in a build without CUDA, the program says so and exits 0 (they build everywhere);
// otherwise it prints the device and runs Google Benchmark.
#pragma once

#include "ctsurg/sim/base/backend.h"
#include "ctsurg/sim/springs/device_simulation.h"

#include <benchmark/benchmark.h>

#include <cstdio>

namespace ctsurg::sim::bench {

inline int run_device_benchmarks(const char* program, int argc, char** argv) {
  if (!backend_available(Backend::cuda)) {
    std::printf("%s: skipped: %s\n", program,
                cuda_built() ? "no CUDA device on this machine" : "this build has no CUDA (CTSURG_CUDA=OFF or no nvcc)");
    return 0;
  }
  const DeviceInfo info = cuda_device_info(0);
  std::printf("device: %s (sm_%d%d, %d SMs, %.1f GiB, peak %.0f GB/s)\n", info.name.c_str(), info.compute_major,
              info.compute_minor, info.multiprocessors, static_cast<double>(info.total_bytes) / (1 << 30),
              info.peak_bandwidth_gbs);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 2;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

}  // namespace ctsurg::sim::bench
