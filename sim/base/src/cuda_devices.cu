// The CUDA devices this process sees (backend.h): their number, queried once, and their description.
// Compiled by nvcc in a build with CUDA; cuda_devices_stubs.cpp answers "none" in a build without it.
#include "ctsurg/sim/base/backend.h"

#include "ctsurg/sim/base/cuda_support.cuh"

#include "ctsurg/core/error.h"

#include <cuda_runtime.h>

#include <string>

namespace ctsurg::sim {
namespace {

int cached_device_count() {
  int count = 0;
  // No driver or no device is an answer (0), not an error.
  if (cudaGetDeviceCount(&count) != cudaSuccess) {
    (void)cudaGetLastError();  // clear the sticky-free error so later calls start clean
    return 0;
  }
  return count;
}

}  // namespace

int cuda_device_count() {
  static const int count = cached_device_count();
  return count;
}

DeviceInfo cuda_device_info(int ordinal) {
  if (cuda_device_count() == 0) {
    require_backend(Backend::cuda, "cuda device");  // throws the "no device" message
  }
  if (ordinal < 0 || ordinal >= cuda_device_count())
    throw InputError("cuda device", "device",
                     "ordinal " + std::to_string(ordinal) + " out of range: " + std::to_string(cuda_device_count()) +
                         " CUDA device(s)");
  cudaDeviceProp prop{};
  CTSURG_CUDA_CHECK(cudaGetDeviceProperties(&prop, ordinal));
  DeviceInfo info;
  info.ordinal = ordinal;
  info.name = prop.name;
  info.compute_major = prop.major, info.compute_minor = prop.minor;
  info.total_bytes = static_cast<int64_t>(prop.totalGlobalMem);
  info.multiprocessors = prop.multiProcessorCount;
  int clock_khz = 0, bus_bits = 0;
  if (cudaDeviceGetAttribute(&clock_khz, cudaDevAttrMemoryClockRate, ordinal) == cudaSuccess &&
      cudaDeviceGetAttribute(&bus_bits, cudaDevAttrGlobalMemoryBusWidth, ordinal) == cudaSuccess)
    info.peak_bandwidth_gbs = 2.0 * clock_khz * 1e3 * (bus_bits / 8.0) / 1e9;  // double data rate
  else
    (void)cudaGetLastError();
  int current = 0;
  CTSURG_CUDA_CHECK(cudaGetDevice(&current));
  CTSURG_CUDA_CHECK(cudaSetDevice(ordinal));
  std::size_t free_bytes = 0, total_bytes = 0;
  CTSURG_CUDA_CHECK(cudaMemGetInfo(&free_bytes, &total_bytes));
  CTSURG_CUDA_CHECK(cudaSetDevice(current));
  info.free_bytes = static_cast<int64_t>(free_bytes);
  return info;
}

}  // namespace ctsurg::sim
