// The backend seam: where a simulation's state lives and its kernels run. The choice is made once,
// when the object that owns the state is built: a simulation engine (simulation_engine.h: the spring
// engine, the FEM engine), FemExplicitDynamics, or a solve that moves its work to the device
// (solve_fem_static); they take a Backend and dispatch, after checking their arguments once (STYLE.md
// rule 5, Open3D's device dispatch). Functions over host arrays (a spring step, a probe, a cut, moving
// a surface, FEM forces) take no Backend: they run on the CPU, and on a device the same kernels
// (kernels/*_impl.h, written once) run inside DeviceSimulation and the FEM's device classes.
#pragma once

#include <cstdint>
#include <string>

namespace ctsurg::sim {

enum class Backend { cpu, cuda };

const char* backend_name(Backend backend);

// Whether this build has the CUDA kernels (CTSURG_CUDA enabled and nvcc found at configure time).
bool cuda_built();
// Number of CUDA devices the runtime sees (queried once, then cached); 0 in a build without CUDA,
// without a driver, or without a device.
int cuda_device_count();

// What a device is (for logs and the benchmarks' bandwidth bound).
struct DeviceInfo {
  int ordinal = 0;                   // CUDA device index
  std::string name;                  // e.g. "NVIDIA H100 80GB HBM3"
  int compute_major = 0, compute_minor = 0;
  int64_t total_bytes = 0;           // global memory
  int64_t free_bytes = 0;            // free when asked
  double peak_bandwidth_gbs = 0;     // 2 x memory clock x bus width (GB/s, 1e9 B/s); 0 when unknown
  int multiprocessors = 0;
};

// The description of device `ordinal` (0 <= ordinal < cuda_device_count()). Throws as require_backend
// (InputError("cuda device", "backend", ...)) when there is no device, InputError("cuda device",
// "device", ...) for an ordinal out of range.
DeviceInfo cuda_device_info(int ordinal = 0);

// Whether `backend` can run here: cpu always; cuda when the build has CUDA and a device is present.
bool backend_available(Backend backend);

// The backend named by a scenario or command line: "cpu", "cuda" or "auto" (cuda when available,
// else cpu). Throws InputError(where, "backend", ...) for another name, and as require_backend for
// "cuda" where it is not available.
Backend resolve_backend(const std::string& name, const std::string& where = "backend");

// Throws InputError(where, "backend", "...") when `backend` cannot run here, saying why: "cuda was
// asked for but this build has no CUDA kernels (CTSURG_CUDA is OFF or nvcc was absent at configure
// time); use cpu or auto", or "... but no CUDA device was found ...". Everything that takes a Backend
// calls it (or resolve_backend) before any work, so asking for cuda never runs the CPU silently.
void require_backend(Backend backend, const std::string& where);

}  // namespace ctsurg::sim
