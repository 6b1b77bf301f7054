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
[[noreturn]] void unreachable() { throw RuntimeError("device simulation: this build has no CUDA"); }
}  // namespace

DeviceInfo DeviceSimulation::Impl::info() const { unreachable(); }
void DeviceSimulation::Impl::upload_grid(const SpringGridModel&, const ParticleState&) { unreachable(); }
void DeviceSimulation::Impl::upload_explicit(const ExplicitSpringModel&, const ParticleState&) { unreachable(); }
void DeviceSimulation::Impl::upload_state(const ParticleState&) { unreachable(); }
void DeviceSimulation::Impl::step(int64_t, const VerletConstants&) { unreachable(); }
void DeviceSimulation::Impl::normals(const VerletConstants&, ParticleNormals&) { unreachable(); }
int64_t DeviceSimulation::Impl::probe(const SphereView&) { unreachable(); }
Grab DeviceSimulation::Impl::grab(const SphereView&, int*) { unreachable(); }
void DeviceSimulation::Impl::apply_grab(int, const SphereView&) { unreachable(); }
void DeviceSimulation::Impl::release_grab(int) { unreachable(); }
int64_t DeviceSimulation::Impl::cut(const TriangleView&) { unreachable(); }
void DeviceSimulation::Impl::set_surface(const int32_t*, const Real*, const Real*, int64_t, const Real*) { unreachable(); }
void DeviceSimulation::Impl::move_surface_async() { unreachable(); }
std::span<const float> DeviceSimulation::Impl::wait_surface() { unreachable(); }
void DeviceSimulation::Impl::download_state(ParticleState&) const { unreachable(); }
void DeviceSimulation::Impl::download_grid_masks(uint32_t*) const { unreachable(); }
void DeviceSimulation::Impl::download_alive(uint8_t*) const { unreachable(); }
void DeviceSimulation::Impl::synchronize() const { unreachable(); }

}  // namespace ctsurg::sim
