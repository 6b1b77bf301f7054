// Position Verlet with velocity damping (Mosegaard & Sorensen 2005, eq. 3, plus the usual damping term):
//   x(t + dt) = x(t) + (1 - damping) (x(t) - x(t - dt)) + a(t) dt^2,   a = f / m + g,
// per particle. A fixed particle (inverse mass 0) stays where it is, gravity included.
#pragma once

#include "ctsurg/sim/base/kernels/kernel_support.h"

#include "ctsurg/sim/base/particle_state.h"

#include <cstdint>

namespace ctsurg::sim {

// Step constants, precomputed once per step on the host.
struct VerletConstants {
  Real dt2;        // dt^2, s^2
  Real inv_dt;     // 1 / dt, 1/s (velocities for spring damping)
  Real keep;       // 1 - damping, in (0, 1]
  Real gx, gy, gz; // gravity, mm/s^2, LPS
};

// Writes particle i's next position into s.nx/ny/nz from the force (fx, fy, fz) in uN.
CTSURG_HD inline void verlet_update(const ParticleStateView& s, const VerletConstants& c, int32_t i, Real fx, Real fy,
                                    Real fz) {
  const Real w = s.inv_mass[i];
  const bool free = w > Real(0);
  const Real g = free ? Real(1) : Real(0);
  const Real xi = s.x[i], yi = s.y[i], zi = s.z[i];
  const Real nx = xi + c.keep * (xi - s.px[i]) + (fx * w + g * c.gx) * c.dt2;
  const Real ny = yi + c.keep * (yi - s.py[i]) + (fy * w + g * c.gy) * c.dt2;
  const Real nz = zi + c.keep * (zi - s.pz[i]) + (fz * w + g * c.gz) * c.dt2;
  s.nx[i] = free ? nx : xi;
  s.ny[i] = free ? ny : yi;
  s.nz[i] = free ? nz : zi;
}

}  // namespace ctsurg::sim
