// The seam between DeviceSimulation's host side (device_simulation.cpp: argument checks, compiled by
// g++ in every build) and its device side (device_simulation_cuda.cu: buffers, streams, graphs and
// kernel launches, compiled by nvcc when the build has CUDA). Plain C++: no CUDA types or syntax, so
// both compilers read it; the CUDA handles live in Impl::Device, defined in the .cu file only.
//
// The host side has checked every argument before calling in here (STYLE.md rule 7).
#pragma once

#include "ctsurg/sim/springs/kernels/sphere_tools_impl.h"
#include "ctsurg/sim/springs/kernels/spring_cutting_impl.h"
#include "ctsurg/sim/springs/kernels/verlet_step_impl.h"

#include "ctsurg/sim/springs/device_simulation.h"

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace ctsurg::sim {

struct DeviceSimulation::Impl {
  enum class UploadedModel { none, grid, explicit_springs };

  explicit Impl(int ordinal);  // selects the device, creates the streams
  ~Impl();

  DeviceInfo info() const;
  void upload_grid(const SpringGridModel& model, const ParticleState& state);
  void upload_explicit(const ExplicitSpringModel& model, const ParticleState& state);
  void upload_state(const ParticleState& state);
  void step(int64_t steps, const VerletConstants& constants);
  void normals(const VerletConstants& constants, ParticleNormals& normals);
  int64_t probe(const SphereView& tool);
  Grab grab(const SphereView& tool, int* handle);  // *handle: the new grab's slot
  void apply_grab(int handle, const SphereView& centre);  // radius unused
  void release_grab(int handle);                   // -1: every grab
  int64_t cut(const TriangleView& blade);
  // particles, weights #V x 8; rest_vertices #V x 3; rest_positions #P x 3 (host arrays).
  void set_surface(const int32_t* particles, const Real* weights, const Real* rest_vertices, int64_t vertices,
                   const Real* rest_positions);
  void move_surface_async();
  std::span<const float> wait_surface();
  void download_state(ParticleState& state) const;
  void download_grid_masks(uint32_t* masks) const;  // #P
  void download_alive(uint8_t* alive) const;        // #S
  void synchronize() const;

  // Host bookkeeping read by the checks in device_simulation.cpp.
  UploadedModel kind = UploadedModel::none;
  int32_t particles = 0;
  int32_t springs = 0;            // explicit model: #S
  bool spring_damping = false;    // the model has damping along some spring (the damped kernel runs)
  std::vector<uint8_t> grabs_held;  // per grab slot (handle): held
  int64_t surface_vertices = -1;  // -1 = no surface set
  int64_t frames_queued = 0;      // move_surface_async calls since set_surface

  struct Device;                  // CUDA handles and device buffers
  std::unique_ptr<Device> device;
};

}  // namespace ctsurg::sim
