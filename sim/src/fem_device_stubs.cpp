// The FEM's device classes in a build without CUDA (CTSURG_CUDA=OFF or no nvcc): FemDeviceDynamics
// (fem_device_dynamics.h) and DeviceConjugateGradient (device_conjugate_gradient.h). Their constructors
// refuse with require_backend's InputError (field "backend": "cuda was asked for but this build has no
// CUDA kernels ..."), so no other member is ever reached. A build with CUDA compiles nothing here; the
// classes live in fem_device_dynamics_cuda.cu and device_conjugate_gradient_cuda.cu.
#include "device_conjugate_gradient.h"
#include "fem_device_dynamics.h"

#if !defined(CTSURG_HAVE_CUDA)

#include "ctsurg/core/error.h"
#include "ctsurg/sim/backend.h"

namespace ctsurg::sim {
namespace {
[[noreturn]] void unreachable() { throw RuntimeError("fem device: this build has no CUDA"); }
}  // namespace

struct FemDeviceDynamics::Device {};

FemDeviceDynamics::FemDeviceDynamics(const FemModel&, const std::vector<Real>&, const std::vector<Real>&,
                                     const FemStepConstants&, double, const FemDeviceGuard&, const char* where) {
  require_backend(Backend::cuda, where);
}
FemDeviceDynamics::~FemDeviceDynamics() = default;
void FemDeviceDynamics::set_inverse_mass(const std::vector<Real>&) { unreachable(); }
void FemDeviceDynamics::zero_nodes(const std::vector<int32_t>&) { unreachable(); }
void FemDeviceDynamics::set_prescribed(const std::vector<int32_t>&, const std::vector<Real>&) { unreachable(); }
void FemDeviceDynamics::set_external_forces(const std::vector<Real>&) { unreachable(); }
void FemDeviceDynamics::set_contact_sphere(const FemSphereView&) { unreachable(); }
FemDeviceStepOutcome FemDeviceDynamics::step(int64_t, int64_t) { unreachable(); }
std::vector<Real> FemDeviceDynamics::displacements() const { unreachable(); }
double FemDeviceDynamics::kinetic_energy() const { unreachable(); }
std::vector<Real> FemDeviceDynamics::internal_forces() { unreachable(); }

struct DeviceConjugateGradient::Device {};

DeviceConjugateGradient::DeviceConjugateGradient(const char* where) { require_backend(Backend::cuda, where); }
DeviceConjugateGradient::~DeviceConjugateGradient() = default;
void DeviceConjugateGradient::set_pattern(int32_t, const int32_t*, const int32_t*) { unreachable(); }
void DeviceConjugateGradient::set_values(const double*) { unreachable(); }
DeviceCgResult DeviceConjugateGradient::solve(const double*, double*, double, int64_t) { unreachable(); }

}  // namespace ctsurg::sim

#endif
