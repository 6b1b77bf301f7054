// The backend seam: where a kernel runs. Every public simulation function takes a Backend and
// dispatches after checking its arguments once (STYLE.md rule 5, Open3D's device dispatch). State
// lives in contiguous arrays (particle_state.h) that a CUDA backend mirrors on the device; the kernels
// (*_impl.h) are written once for both.
#pragma once

#include <string>

namespace ctsurg::sim {

enum class Backend { cpu, cuda };

const char* backend_name(Backend backend);

// Whether this build can run `backend` (cpu always; cuda never in this build: no .cu compiled yet).
bool backend_available(Backend backend);

// Throws InputError(where, "backend", "...") when `backend` is not available in this build, e.g.
// "step: backend: cuda was asked for but this build has no CUDA kernels (CTSURG_CUDA is OFF or nvcc
// absent); use cpu". Every dispatcher calls it first.
void require_backend(Backend backend, const std::string& where);

}  // namespace ctsurg::sim
