// FemDeviceDynamics (fem_device_dynamics.h) in a build without CUDA (CTSURG_CUDA=OFF or no nvcc): the
// constructor refuses with require_backend's InputError (field "backend": "cuda was asked for but this
// build has no CUDA kernels ..."), so no other member is ever reached. A build with CUDA compiles
// fem_device_dynamics_cuda.cu instead.
#include "fem_device_dynamics.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/base/backend.h"

namespace ctsurg::sim {
namespace {
[[noreturn]] void no_cuda_dynamics() { throw RuntimeError("fem device dynamics: this build has no CUDA"); }
}  // namespace

struct FemDeviceDynamics::Device {};

FemDeviceDynamics::FemDeviceDynamics(const FemModel&, const std::vector<Real>&, const std::vector<Real>&,
                                     const FemStepConstants&, double, const FemDeviceGuard&, const char* where) {
  require_backend(Backend::cuda, where);
}
FemDeviceDynamics::~FemDeviceDynamics() = default;
void FemDeviceDynamics::set_inverse_mass(const std::vector<Real>&) { no_cuda_dynamics(); }
void FemDeviceDynamics::zero_nodes(const std::vector<int32_t>&) { no_cuda_dynamics(); }
void FemDeviceDynamics::set_prescribed(const std::vector<int32_t>&, const std::vector<Real>&) { no_cuda_dynamics(); }
void FemDeviceDynamics::set_external_forces(const std::vector<Real>&) { no_cuda_dynamics(); }
void FemDeviceDynamics::set_contact_sphere(const FemSphereView&) { no_cuda_dynamics(); }
FemDeviceStepOutcome FemDeviceDynamics::step(int64_t, int64_t) { no_cuda_dynamics(); }
std::vector<Real> FemDeviceDynamics::displacements() const { no_cuda_dynamics(); }
double FemDeviceDynamics::kinetic_energy() const { no_cuda_dynamics(); }
std::vector<Real> FemDeviceDynamics::internal_forces() { no_cuda_dynamics(); }

}  // namespace ctsurg::sim
