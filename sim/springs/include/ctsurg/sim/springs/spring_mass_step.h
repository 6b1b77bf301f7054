// One time step of a spring-mass model: gather the spring forces per particle, integrate with
// position Verlet (Mosegaard & Sorensen 2005, eq. 3) with damping and gravity, optionally output the
// approximate normals (eq. 5) from the same gather. One pass over the particles per step.
//
// The kernels are written once (src/spring_forces_impl.h, verlet_step_impl.h,
// particle_normals_impl.h) and compiled for the CPU with OpenMP in src/spring_mass_step_cpu.cpp.
// Results do not depend on the number of threads: each particle's new position is computed by one
// thread from the old positions, in the same order of operations, whatever the partition.
#pragma once

#include "ctsurg/sim/base/particle_state.h"
#include "ctsurg/sim/springs/explicit_spring_model.h"
#include "ctsurg/sim/springs/spring_grid_model.h"

#include <array>
#include <vector>

namespace ctsurg::sim {

struct StepParameters {
  double dt = 0;                          // s, > 0 (stability.h gives the critical step)
  double damping = 0;                     // Verlet velocity damping per step, in [0, 1)
  std::array<double, 3> gravity{0, 0, 0}; // mm/s^2, LPS; e.g. {0, 0, -9810} pulls towards inferior
  int threads = 0;                        // OpenMP threads; 0 = one per 8,192 particles, at most OpenMP's default
};

// Approximate normals, one per particle (unit, or zero where the neighbour directions cancel).
struct ParticleNormals {
  std::vector<Real> x, y, z;  // #P
};

// Advances `state` by one step of `parameters.dt` (state.advance() included: afterwards state.x is
// x(t + dt)). When `normals` is given it receives the normals at the positions of time t.
// state has #P = model.particle_count() particles. Throws InputError("step", field, ...) for a
// mismatch or a parameter out of range (checked once per call). On the host's arrays, on the CPU; the
// same step on a CUDA device is DeviceSimulation's (device_simulation.h), which keeps the state there.
void step(const SpringGridModel& model, ParticleState& state, const StepParameters& parameters,
          ParticleNormals* normals = nullptr);
void step(const ExplicitSpringModel& model, ParticleState& state, const StepParameters& parameters,
          ParticleNormals* normals = nullptr);

}  // namespace ctsurg::sim
