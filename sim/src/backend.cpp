#include "ctsurg/sim/backend.h"

#include "ctsurg/core/error.h"

namespace ctsurg::sim {

const char* backend_name(Backend backend) { return backend == Backend::cpu ? "cpu" : "cuda"; }

bool backend_available(Backend backend) { return backend == Backend::cpu; }

void require_backend(Backend backend, const std::string& where) {
  if (backend_available(backend)) return;
  throw InputError(where, "backend",
                   std::string(backend_name(backend)) +
                       " was asked for but this build has no CUDA kernels (CTSURG_CUDA is OFF, nvcc is absent, "
                       "or the CUDA sim backend is not built yet); use cpu");
}

}  // namespace ctsurg::sim
