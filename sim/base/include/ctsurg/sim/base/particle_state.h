// The state of a particle system: positions at the current and previous time step (position Verlet
// needs both, Mosegaard & Sorensen 2005, eq. 3), masses, and a buffer for the next step; structure of
// arrays, one contiguous array per coordinate, index = particle id.
//
// Units (every sim/ header): lengths in mm (LPS frame, as every ctsurg file), time in s, mass in g.
// Hence force is g*mm/s^2 = 1e-6 N = 1 uN, stiffness g/s^2 = uN/mm (= mN/m), damping coefficient
// g/s, energy g*mm^2/s^2 = 1e-9 J = 1 nJ, density g/mm^3 (water: 1e-3), gravity 9810 mm/s^2.
#pragma once

#include "ctsurg/sim/base/backend.h"
#include "ctsurg/sim/base/real.h"

#include <cstdint>
#include <vector>

namespace ctsurg::sim {

// What a kernel sees: raw pointers into the state's arrays (trivially copyable, passed by value).
struct ParticleStateView {
  const Real* x;   // #P current positions, LPS mm
  const Real* y;
  const Real* z;
  const Real* px;  // #P positions one step earlier, LPS mm
  const Real* py;
  const Real* pz;
  Real* nx;        // #P positions one step later (written by the step kernels), LPS mm
  Real* ny;
  Real* nz;
  const Real* inv_mass;  // #P 1/g; 0 = fixed (the particle never moves under forces)
  int32_t count;         // #P
};

// The state on the CPU (std::vector). A CUDA backend will hold the same arrays on the device.
struct ParticleState {
  std::vector<Real> x, y, z;      // #P current positions, LPS mm
  std::vector<Real> px, py, pz;   // #P previous positions, LPS mm
  std::vector<Real> nx, ny, nz;   // #P next positions (scratch of the step kernels), LPS mm
  std::vector<Real> mass;         // #P g (> 0), also for fixed particles
  std::vector<Real> inv_mass;     // #P 1/g; 0 = fixed

  ParticleState() = default;
  // At rest at `positions` (#P x 3, row-major, LPS mm) with masses `mass` (#P, g, > 0): previous =
  // current (zero velocity), nothing fixed. Throws InputError("particle state", ...) on a size
  // mismatch or a mass that is not finite and positive.
  ParticleState(const std::vector<Real>& positions, const std::vector<Real>& mass);

  int32_t count() const { return static_cast<int32_t>(x.size()); }
  ParticleStateView view();
  // After a step kernel wrote the next positions: previous <- current <- next (pointer swaps).
  void advance();
  // Sets particle i's velocity to v (mm/s) for a step dt (s): previous = current - v dt.
  void set_velocity(int32_t i, double vx, double vy, double vz, double dt);
  // Fixes particle i (inverse mass 0) or frees it again (inverse mass 1 / mass).
  void set_fixed(int32_t i, bool fixed);
};

}  // namespace ctsurg::sim
