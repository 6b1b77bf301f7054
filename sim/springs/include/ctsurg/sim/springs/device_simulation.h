// A spring-mass simulation that lives on a CUDA device (issue 6): device mirrors of a spring model
// (implicit grid or explicit springs) and of its ParticleState, stepped on the device for many steps
// per call, with the tools (probe, grab, cut) and the surface coupling running there too. Only what
// the caller asks for comes back: surface frames (asynchronously, into pinned host memory, on a second
// stream) and, on request, the state or the spring masks.
//
// The kernels are the CPU backend's (src/spring_forces_impl.h, verlet_step_impl.h,
// particle_normals_impl.h, sphere_tools_impl.h, spring_cutting_impl.h, surface_coupling_impl.h),
// compiled by nvcc in src/device_simulation_cuda.cu: one CUDA thread per particle (spring step, probe,
// grid cut), per spring (explicit cut), per grabbed particle or per surface vertex, calling the same
// per-index functions as the OpenMP launchers (STYLE.md rule 5). The .cu file is compiled without FMA
// contraction (-fmad=false), as the CPU step file is (-ffp-contract=off), so a step gives the CPU's
// bits up to the order-independent rounding both sides share (tests/sim/test_device_simulation.cpp
// states the tolerance).
//
// A build without CUDA (CTSURG_CUDA=OFF or no nvcc) still has this class: its constructor throws
// InputError("device simulation", "backend", "cuda was asked for but this build has no CUDA ...").
// A CUDA build on a machine without a device throws the same with "... no CUDA device was found".
//
// Units: LPS mm, s, g (particle_state.h). Everything here is for one host thread at a time.
#pragma once

#include "ctsurg/sim/base/backend.h"
#include "ctsurg/sim/base/particle_state.h"
#include "ctsurg/sim/springs/explicit_spring_model.h"
#include "ctsurg/sim/springs/sphere_tools.h"
#include "ctsurg/sim/springs/spring_cutting.h"
#include "ctsurg/sim/springs/spring_grid_model.h"
#include "ctsurg/sim/springs/spring_mass_step.h"

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>

namespace ctsurg::sim {

struct SurfaceCoupling;  // surface_coupling.h (not included: it pulls in HDF5, which nvcc need not read)

class DeviceSimulation {
 public:
  // Selects CUDA device `ordinal` and creates the compute and copy streams. Throws InputError
  // ("device simulation", "backend", ...) in a build without CUDA or without a device, and
  // InputError("device simulation", "device", ...) for an ordinal out of range.
  explicit DeviceSimulation(int ordinal = 0);
  ~DeviceSimulation();
  DeviceSimulation(DeviceSimulation&&) noexcept;
  DeviceSimulation& operator=(DeviceSimulation&&) noexcept;
  DeviceSimulation(const DeviceSimulation&) = delete;
  DeviceSimulation& operator=(const DeviceSimulation&) = delete;

  DeviceInfo device_info() const;

  // Copies the model and its state to the device (replacing what was there; a grab and a surface are
  // released). state.count() must equal the model's particle count, else InputError("device upload",
  // "state", ...). The explicit model's rows are used as CSR (its CPU chunk layout stays on the host).
  void upload(const SpringGridModel& model, const ParticleState& state);
  void upload(const ExplicitSpringModel& model, const ParticleState& state);
  // Replaces only the state (same particle count as the uploaded model).
  void upload_state(const ParticleState& state);
  int32_t particle_count() const;

  // Advances `steps` (>= 0) steps, every one as step() in spring_mass_step.h (parameters checked as
  // there; `threads` is ignored). While a grab is held, its particles are placed at centre + offset
  // after every step (as apply_grab() after each step on the CPU). The launches are queued on the
  // compute stream (as CUDA graphs of a few steps, replayed: one launch per graph, not per kernel)
  // and the call returns without waiting; the next call that reads results waits.
  void step(int64_t steps, const StepParameters& parameters);
  // Normals (eq. 5) of the current positions, as step(..., &normals) on the CPU computes them for
  // time t, from one extra gather (the positions are not changed). Blocks; copies #P x 3 back.
  ParticleNormals normals(const StepParameters& parameters);

  // Tools (sphere_tools.h, spring_cutting.h), on the device's current positions.
  // Projects the free particles inside the sphere onto its surface; returns how many moved.
  int64_t probe(const Sphere& tool);
  // Captures the free particles strictly inside the sphere (increasing ids) with their offsets, holds the
  // grab on the device next to any grabs already held, and returns a copy; *handle (when given) names
  // it: the lowest handle not held, so the first grab is 0. The inside flags (1 byte per particle)
  // come back to the host for an ordered compaction: grabbing is an event, not a per-step operation.
  // After each step the held grabs are placed in handle order (a particle in two grabs follows the
  // later one, as the CPU's apply_grab calls in that order).
  Grab grab(const Sphere& tool, int* handle = nullptr);
  // Places held grab `handle` at `centre` now, and after every later step, until it is released.
  // InputError("device grab", "grab", ...) when that grab is not held.
  void apply_grab(const std::array<double, 3>& centre, int handle = 0);
  // Releases grab `handle`, or every grab (-1).
  void release_grab(int handle = -1);
  bool grab_held() const;  // any grab
  // Cuts the springs crossing the triangle (on the device's model); returns the number cut.
  int64_t cut_springs_crossing_triangle(const Triangle& blade);

  // Surface coupling (surface_coupling.h): uploads the coupling (its particles must be the uploaded
  // model's, with rest positions `rest_positions`, #P x 3 LPS mm).
  void set_surface(const SurfaceCoupling& coupling, const std::vector<Real>& rest_positions);
  // Queues the vertex kernel after the steps queued so far and an asynchronous copy of the frame
  // (#V x 3 floats) into pinned host memory on the copy stream; returns at once. Two frames can be in
  // flight (double-buffered on both sides).
  void move_surface_async();
  // Waits for the latest frame queued by move_surface_async() and returns it (#V x 3 LPS mm). The
  // span stays valid until the second move_surface_async() call after this one.
  std::span<const float> wait_surface();

  // Copies the current and previous positions back into `state` (x, y, z, px, py, pz; its mass and
  // inverse mass as uploaded). state is resized to the particle count. Blocks.
  void download_state(ParticleState& state) const;
  // Copies the spring presence back (the grid's masks, or the explicit model's alive flags followed by
  // sync_cut_springs). The model must be the uploaded one (same sizes). Blocks.
  void download_springs(SpringGridModel& model) const;
  void download_springs(ExplicitSpringModel& model) const;
  // Blocks until everything queued has finished.
  void synchronize() const;

  struct Impl;  // device side (src/device_simulation_cuda.cu)

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace ctsurg::sim
