// Per-particle kernels of the spherical tools (sphere_tools.h).
#pragma once

#include "ctsurg/sim/base/kernels/kernel_support.h"

#include <cstdint>

namespace ctsurg::sim {

struct SphereView {
  Real cx, cy, cz;  // centre, LPS mm
  Real radius;      // mm
};

CTSURG_HD inline bool inside_sphere(Real x, Real y, Real z, const SphereView& s) {
  const Real dx = x - s.cx, dy = y - s.cy, dz = z - s.cz;
  return dx * dx + dy * dy + dz * dz < s.radius * s.radius;
}

// True when particle i is free (a fixed particle stays where the scene holds it, as the FEM's
// grabs leave fixed nodes alone) and inside the sphere: the particles a grab captures.
CTSURG_HD inline bool grabbable(const Real* x, const Real* y, const Real* z, const Real* inv_mass, const SphereView& s,
                                int64_t i) {
  return inv_mass[i] != Real(0) && inside_sphere(x[i], y[i], z[i], s);
}

// Moves particle i onto the sphere when it is inside and free; returns 1 when it moved.
CTSURG_HD inline int probe_particle(Real* x, Real* y, Real* z, const Real* inv_mass, const SphereView& s, int64_t i) {
  if (inv_mass[i] == Real(0) || !inside_sphere(x[i], y[i], z[i], s)) return 0;
  const Real dx = x[i] - s.cx, dy = y[i] - s.cy, dz = z[i] - s.cz;
  const Real len = kernel_sqrt(dx * dx + dy * dy + dz * dz);
  if (len > Real(0)) {
    const Real k = s.radius / len;
    x[i] = s.cx + dx * k, y[i] = s.cy + dy * k, z[i] = s.cz + dz * k;
  } else {
    z[i] = s.cz + s.radius;  // at the centre: no direction; push to the top (+z, superior)
  }
  return 1;
}

// Sets grabbed particle ids[g] to the centre plus its offset.
CTSURG_HD inline void place_grabbed(Real* x, Real* y, Real* z, const int32_t* ids, const Real* offsets,
                                    const SphereView& s, int64_t g) {
  const int32_t p = ids[g];
  x[p] = s.cx + offsets[3 * g], y[p] = s.cy + offsets[3 * g + 1], z[p] = s.cz + offsets[3 * g + 2];
}

}  // namespace ctsurg::sim
