#include "ctsurg/sim/base/backend.h"

#include "ctsurg/core/error.h"

namespace ctsurg::sim {

const char* backend_name(Backend backend) { return backend == Backend::cpu ? "cpu" : "cuda"; }

bool cuda_built() {
#if defined(CTSURG_HAVE_CUDA)
  return true;
#else
  return false;
#endif
}

// cuda_device_count() and cuda_device_info() are in cuda_devices.cu (a build with CUDA) or
// cuda_devices_stubs.cpp (without).

bool backend_available(Backend backend) {
  if (backend == Backend::cpu) return true;
  return cuda_built() && cuda_device_count() > 0;
}

namespace {

// Why cuda cannot run here, or "" when it can.
std::string cuda_unavailable_reason() {
  if (!cuda_built())
    return "cuda was asked for but this build has no CUDA kernels (CTSURG_CUDA is OFF or nvcc was absent at "
           "configure time); use cpu or auto";
  if (cuda_device_count() == 0)
    return "cuda was asked for but no CUDA device was found (no GPU, no driver, or CUDA_VISIBLE_DEVICES hides "
           "it); use cpu or auto";
  return "";
}

}  // namespace

void require_backend(Backend backend, const std::string& where) {
  if (backend == Backend::cpu) return;
  const std::string reason = cuda_unavailable_reason();
  if (!reason.empty()) throw InputError(where, "backend", reason);
}

Backend resolve_backend(const std::string& name, const std::string& where) {
  if (name == "cpu") return Backend::cpu;
  if (name == "auto") return backend_available(Backend::cuda) ? Backend::cuda : Backend::cpu;
  if (name == "cuda") {
    const std::string reason = cuda_unavailable_reason();
    if (!reason.empty()) throw InputError(where, "backend", reason);
    return Backend::cuda;
  }
  throw InputError(where, "backend", "must be cpu, cuda or auto, got '" + name + "'");
}

}  // namespace ctsurg::sim
