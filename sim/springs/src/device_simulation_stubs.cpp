// DeviceSimulation's device side in a build without CUDA (CTSURG_CUDA=OFF or no nvcc): the constructor
// refuses with require_backend's InputError ("device simulation", "backend": "cuda was asked for but
// this build has no CUDA kernels ..."), so no other member is ever reached. A build with CUDA compiles
// device_simulation_cuda.cu instead.
#include "device_simulation_cuda.cuh"

#include "ctsurg/core/error.h"

namespace ctsurg::sim {

struct DeviceSimulation::Impl::Device {};

DeviceSimulation::Impl::Impl(int) { require_backend(Backend::cuda, "device simulation"); }
DeviceSimulation::Impl::~Impl() = default;

namespace {
[[noreturn]] void no_cuda_simulation() { throw RuntimeError("device simulation: this build has no CUDA"); }
}  // namespace

DeviceInfo DeviceSimulation::Impl::info() const { no_cuda_simulation(); }
void DeviceSimulation::Impl::upload_grid(const SpringGridModel&, const ParticleState&) { no_cuda_simulation(); }
void DeviceSimulation::Impl::upload_explicit(const ExplicitSpringModel&, const ParticleState&) { no_cuda_simulation(); }
void DeviceSimulation::Impl::upload_state(const ParticleState&) { no_cuda_simulation(); }
void DeviceSimulation::Impl::step(int64_t, const VerletConstants&) { no_cuda_simulation(); }
void DeviceSimulation::Impl::normals(const VerletConstants&, ParticleNormals&) { no_cuda_simulation(); }
int64_t DeviceSimulation::Impl::probe(const SphereView&) { no_cuda_simulation(); }
Grab DeviceSimulation::Impl::grab(const SphereView&, int*) { no_cuda_simulation(); }
void DeviceSimulation::Impl::apply_grab(int, const SphereView&) { no_cuda_simulation(); }
void DeviceSimulation::Impl::release_grab(int) { no_cuda_simulation(); }
int64_t DeviceSimulation::Impl::cut(const TriangleView&) { no_cuda_simulation(); }
void DeviceSimulation::Impl::set_surface(const int32_t*, const Real*, const Real*, int64_t, const Real*) { no_cuda_simulation(); }
void DeviceSimulation::Impl::move_surface_async() { no_cuda_simulation(); }
std::span<const float> DeviceSimulation::Impl::wait_surface() { no_cuda_simulation(); }
void DeviceSimulation::Impl::download_state(ParticleState&) const { no_cuda_simulation(); }
void DeviceSimulation::Impl::download_grid_masks(uint32_t*) const { no_cuda_simulation(); }
void DeviceSimulation::Impl::download_alive(uint8_t*) const { no_cuda_simulation(); }
void DeviceSimulation::Impl::synchronize() const { no_cuda_simulation(); }

}  // namespace ctsurg::sim
