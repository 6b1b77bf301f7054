// DeviceSimulation, host side: every argument is checked here, once, before the device side
// (device_simulation_cuda.cu) is called (STYLE.md rule 7). In a build without CUDA the device side is
// device_simulation_stubs.cpp: the constructor refuses with a clear message, so no other stub is ever
// reached.
#include "ctsurg/sim/springs/device_simulation.h"

#include "device_simulation_cuda.cuh"
#include "verlet_constants.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/surface/surface_coupling.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

namespace ctsurg::sim {
namespace {

SphereView sphere_view(const std::array<double, 3>& centre, double radius, const char* where) {
  for (double c : centre)
    if (!std::isfinite(c)) throw InputError(where, "centre", "must be finite");
  if (!(std::isfinite(radius) && radius > 0))
    throw InputError(where, "radius", "must be finite and > 0, got " + std::to_string(radius));
  return {static_cast<Real>(centre[0]), static_cast<Real>(centre[1]), static_cast<Real>(centre[2]),
          static_cast<Real>(radius)};
}

void check_state(const ParticleState& state, int32_t particles, const char* where) {
  if (state.count() != particles)
    throw InputError(where, "state", "has " + std::to_string(state.count()) + " particles, the model " +
                                         std::to_string(particles));
  const auto n = static_cast<std::size_t>(particles);
  for (const auto* v : {&state.px, &state.py, &state.pz, &state.y, &state.z, &state.inv_mass})
    if (v->size() != n) throw InputError(where, "state", "arrays of different lengths");
}

}  // namespace

DeviceSimulation::DeviceSimulation(int ordinal) : impl_(std::make_unique<Impl>(ordinal)) {}
DeviceSimulation::~DeviceSimulation() = default;
DeviceSimulation::DeviceSimulation(DeviceSimulation&&) noexcept = default;
DeviceSimulation& DeviceSimulation::operator=(DeviceSimulation&&) noexcept = default;

DeviceInfo DeviceSimulation::device_info() const { return impl_->info(); }

void DeviceSimulation::upload(const SpringGridModel& model, const ParticleState& state) {
  const int32_t n = model.particle_count();
  check_state(state, n, "device upload");
  if (model.neighbours.size() != static_cast<std::size_t>(kGridDirections) * n || model.spring_mask.size() != static_cast<std::size_t>(n))
    throw InputError("device upload", "model", "neighbour table or spring masks do not match the particle count");
  impl_->upload_grid(model, state);
}

void DeviceSimulation::upload(const ExplicitSpringModel& model, const ParticleState& state) {
  const int32_t n = model.particle_count();
  check_state(state, n, "device upload");
  const auto s = static_cast<std::size_t>(model.spring_count());
  if (model.row_offsets.size() != static_cast<std::size_t>(n) + 1 || model.row_neighbour.size() != 2 * s ||
      model.row_spring.size() != 2 * s || model.spring_ends.size() != 2 * s || model.stiffness.size() != s ||
      model.rest_length.size() != s || model.damping.size() != s)
    throw InputError("device upload", "model", "CSR rows or spring arrays do not match the spring count");
  impl_->upload_explicit(model, state);
}

void DeviceSimulation::upload_state(const ParticleState& state) {
  if (impl_->kind == Impl::UploadedModel::none) throw InputError("device upload", "model", "upload a model first");
  check_state(state, impl_->particles, "device upload");
  impl_->upload_state(state);
}

int32_t DeviceSimulation::particle_count() const { return impl_->particles; }

void DeviceSimulation::step(int64_t steps, const StepParameters& parameters) {
  const VerletConstants c = verlet_constants(parameters, "device step");
  if (steps < 0) throw InputError("device step", "steps", "must be >= 0, got " + std::to_string(steps));
  if (impl_->kind == Impl::UploadedModel::none) throw InputError("device step", "model", "upload a model first");
  if (steps > 0) impl_->step(steps, c);
}

ParticleNormals DeviceSimulation::normals(const StepParameters& parameters) {
  const VerletConstants c = verlet_constants(parameters, "device normals");
  if (impl_->kind == Impl::UploadedModel::none) throw InputError("device normals", "model", "upload a model first");
  ParticleNormals n;
  impl_->normals(c, n);
  return n;
}

int64_t DeviceSimulation::probe(const Sphere& tool) {
  const SphereView s = sphere_view(tool.centre, tool.radius, "device probe");
  if (impl_->kind == Impl::UploadedModel::none) throw InputError("device probe", "model", "upload a model first");
  return impl_->probe(s);
}

Grab DeviceSimulation::grab(const Sphere& tool, int* handle) {
  const SphereView s = sphere_view(tool.centre, tool.radius, "device grab");
  if (impl_->kind == Impl::UploadedModel::none) throw InputError("device grab", "model", "upload a model first");
  return impl_->grab(s, handle);
}

void DeviceSimulation::apply_grab(const std::array<double, 3>& centre, int handle) {
  const SphereView s = sphere_view(centre, 1.0, "device grab");
  const auto& held = impl_->grabs_held;
  if (handle < 0 || static_cast<std::size_t>(handle) >= held.size() || !held[static_cast<std::size_t>(handle)])
    throw InputError("device grab", "grab", "grab " + std::to_string(handle) + " is not held (call grab() first)");
  impl_->apply_grab(handle, s);
}

void DeviceSimulation::release_grab(int handle) {
  if (handle < -1) throw InputError("device grab", "grab", "handle " + std::to_string(handle) + " (use -1 for every grab)");
  if (!impl_->grabs_held.empty()) impl_->release_grab(handle);
}

bool DeviceSimulation::grab_held() const {
  const auto& held = impl_->grabs_held;
  return std::any_of(held.begin(), held.end(), [](uint8_t h) { return h != 0; });
}

int64_t DeviceSimulation::cut_springs_crossing_triangle(const Triangle& blade) {
  TriangleView v{};
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(blade.a[a]) || !std::isfinite(blade.b[a]) || !std::isfinite(blade.c[a]))
      throw InputError("device cut", "blade", "triangle corners must be finite");
    v.a[a] = blade.a[a], v.b[a] = blade.b[a], v.c[a] = blade.c[a];
  }
  if (impl_->kind == Impl::UploadedModel::none) throw InputError("device cut", "model", "upload a model first");
  return impl_->cut(v);
}

void DeviceSimulation::set_surface(const SurfaceCoupling& coupling, const std::vector<Real>& rest_positions) {
  if (impl_->kind == Impl::UploadedModel::none) throw InputError("device surface", "model", "upload a model first");
  const int32_t n = impl_->particles;
  if (rest_positions.size() != 3 * static_cast<std::size_t>(n))
    throw InputError("device surface", "rest_positions", "expected 3 x the model's particle count");
  const auto v = static_cast<std::size_t>(coupling.vertex_count());
  if (coupling.rest_vertices.size() != 3 * v || coupling.particles.size() != 8 * v || coupling.weights.size() != 8 * v)
    throw InputError("device surface", "coupling", "expected 8 particles and weights and 3 coordinates per vertex");
  if (std::any_of(coupling.particles.begin(), coupling.particles.end(), [n](int32_t p) { return p >= n; }))
    throw InputError("device surface", "coupling", "names a particle the model does not have");
  impl_->set_surface(coupling.particles.data(), coupling.weights.data(), coupling.rest_vertices.data(),
                     coupling.vertex_count(), rest_positions.data());
}

void DeviceSimulation::move_surface_async() {
  if (impl_->surface_vertices < 0) throw InputError("device surface", "surface", "no surface set (call set_surface() first)");
  impl_->move_surface_async();
}

std::span<const float> DeviceSimulation::wait_surface() {
  if (impl_->frames_queued == 0) throw InputError("device surface", "frame", "no frame queued (call move_surface_async() first)");
  return impl_->wait_surface();
}

void DeviceSimulation::download_state(ParticleState& state) const {
  if (impl_->kind == Impl::UploadedModel::none) throw InputError("device download", "model", "upload a model first");
  impl_->download_state(state);
}

void DeviceSimulation::download_springs(SpringGridModel& model) const {
  if (impl_->kind != Impl::UploadedModel::grid || model.particle_count() != impl_->particles)
    throw InputError("device download", "model", "is not the uploaded grid model");
  impl_->download_grid_masks(model.spring_mask.data());
}

void DeviceSimulation::download_springs(ExplicitSpringModel& model) const {
  if (impl_->kind != Impl::UploadedModel::explicit_springs || model.particle_count() != impl_->particles ||
      model.spring_count() != impl_->springs)
    throw InputError("device download", "model", "is not the uploaded explicit model");
  impl_->download_alive(model.alive.data());
  sync_cut_springs(model);
}

void DeviceSimulation::synchronize() const { impl_->synchronize(); }

}  // namespace ctsurg::sim
