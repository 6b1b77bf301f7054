// Per-particle spring forces, gathered (STYLE.md rules 5 and 6): the force on particle i is the sum
// over its springs, read from i's own neighbour list, so no two threads write the same particle.
//
// Hooke's law along the spring (Mosegaard & Sorensen 2005, eqs. 2 and 4, with a k_ij per spring), with
// optional damping along the spring direction:
//   d = x_j - x_i,  u = d / |d|,
//   f_i += k (|d| - l) u  +  c ((v_j - v_i) . u) u,   v = (x(t) - x(t - dt)) / dt.
// (The papers' eq. 2 writes the force with a factor 1/2 k_ij; here k is the spring constant itself, so
// their k is twice ours.) A spring of zero length has no direction: it gives zero force (never NaN). The same loop sums the
// unit vectors from the neighbours to the particle, -u, for the approximate normals of eq. 5,
// when kNormals.
//
// The loops are branch-free: an absent spring (mask bit clear, cut, or no neighbour) reads the
// particle itself (d = 0), which gives exactly zero, so the CPU vectorises across particles and a GPU
// warp does not diverge.
#pragma once

#include "ctsurg/sim/base/kernels/kernel_support.h"

#include "ctsurg/sim/base/particle_state.h"
#include "ctsurg/sim/springs/explicit_spring_model.h"
#include "ctsurg/sim/springs/spring_grid_model.h"

#include <cstdint>

namespace ctsurg::sim {

// Force on a particle (g mm/s^2 = uN) and the sum of unit vectors from its neighbours to it.
struct SpringForceSum {
  Real fx = 0, fy = 0, fz = 0;
  Real ux = 0, uy = 0, uz = 0;
};

// One spring's contribution to particle i. (dx, dy, dz) = x_j - x_i (mm); (dvx, dvy, dvz) = (v_j - v_i)
// (mm/s, only read when kDamping); present = 1 (spring there) or 0 (absent: contributes exactly 0),
// a Real rather than a bool: GCC 12 does not vectorise the bool-to-float conversion in this loop.
template <bool kDamping, bool kNormals>
CTSURG_HD inline void add_spring(Real dx, Real dy, Real dz, Real dvx, Real dvy, Real dvz, Real k, Real rest, Real c,
                                 Real present, SpringForceSum& sum) {
  // Arithmetic masks rather than branches or short-circuits: every lane computes every operation (on
  // safe operands), which keeps the SIMD loop free of control flow.
  const Real len2 = dx * dx + dy * dy + dz * dz;
  const Real nonzero = static_cast<Real>(len2 > Real(0));
  const Real root = kernel_sqrt(len2 + (Real(1) - nonzero));  // sqrt(1) for a zero-length spring
  const Real inv_len = (Real(1) / root) * (nonzero * present);
  const Real len = len2 * inv_len;
  Real magnitude = k * (len - rest) * inv_len;  // times d gives k (|d| - l) u
  if constexpr (kDamping) {
    const Real rate = (dvx * dx + dvy * dy + dvz * dz) * inv_len * inv_len;  // ((v_j - v_i) . u) / |d|
    magnitude += c * rate;
  }
  sum.fx += magnitude * dx, sum.fy += magnitude * dy, sum.fz += magnitude * dz;
  if constexpr (kNormals) sum.ux -= dx * inv_len, sum.uy -= dy * inv_len, sum.uz -= dz * inv_len;
}

// Implicit connections, one spring: the spring of particle i in direction d (0..17), added to `sum`.
// j = i's neighbour in direction d when the spring is present (bit = 1), else any valid particle (the
// contribution is then zero). The CPU reads j from the neighbour table (a gather), or, where the
// springs d of 16 consecutive particles lead to 16 consecutive particles (rows of a solid region:
// most chunks), as base + k (contiguous loads); a GPU thread calls grid_spring_forces below. Each
// particle's sum runs over d = 0..17 in order on every path: the same bits (up to the sign of an
// exact zero).
template <bool kDamping, bool kNormals>
CTSURG_HD inline void add_grid_spring_to(const SpringGridView& g, const ParticleStateView& s, Real inv_dt, int32_t i,
                                         int d, int32_t j, uint32_t bit, SpringForceSum& sum) {
  const Real xi = s.x[i], yi = s.y[i], zi = s.z[i];
  Real dvx = 0, dvy = 0, dvz = 0;
  if constexpr (kDamping) {
    dvx = ((s.x[j] - s.px[j]) - (xi - s.px[i])) * inv_dt;
    dvy = ((s.y[j] - s.py[j]) - (yi - s.py[i])) * inv_dt;
    dvz = ((s.z[j] - s.pz[j]) - (zi - s.pz[i])) * inv_dt;
  }
  add_spring<kDamping, kNormals>(s.x[j] - xi, s.y[j] - yi, s.z[j] - zi, dvx, dvy, dvz, g.stiffness[d],
                                 g.rest_length[d], g.damping[d], static_cast<Real>(bit), sum);
}

// The same, with j read from the neighbour table.
template <bool kDamping, bool kNormals>
CTSURG_HD inline void add_grid_spring(const SpringGridView& g, const ParticleStateView& s, Real inv_dt, int32_t i,
                                      int d, SpringForceSum& sum) {
  const uint32_t bit = (g.spring_mask[i] >> d) & 1u;
  // j = bit ? neighbour : i, as integer arithmetic on an unconditional load, so that the compiler
  // emits a gather, not a branch (-1 = no neighbour is never dereferenced: its bit is clear).
  const int32_t neighbour = g.neighbours[static_cast<int64_t>(d) * g.count + i];
  const int32_t j = i + ((neighbour - i) & -static_cast<int32_t>(bit));
  add_grid_spring_to<kDamping, kNormals>(g, s, inv_dt, i, d, j, bit, sum);
}

// Implicit connections: the 18 grid springs of particle i.
template <bool kDamping, bool kNormals>
CTSURG_HD inline SpringForceSum grid_spring_forces(const SpringGridView& g, const ParticleStateView& s, Real inv_dt,
                                                   int32_t i) {
  SpringForceSum sum;
  CTSURG_UNROLL
  for (int d = 0; d < kGridDirections; ++d) add_grid_spring<kDamping, kNormals>(g, s, inv_dt, i, d, sum);
  return sum;
}

// Explicit connections: the springs in particle i's CSR row.
template <bool kDamping, bool kNormals>
CTSURG_HD inline SpringForceSum explicit_spring_forces(const ExplicitSpringView& m, const ParticleStateView& s,
                                                       Real inv_dt, int32_t i) {
  SpringForceSum sum;
  const Real xi = s.x[i], yi = s.y[i], zi = s.z[i];
  const int32_t end = m.row_offsets[i + 1];
  for (int32_t e = m.row_offsets[i]; e < end; ++e) {
    const int32_t j = m.row_neighbour[e];
    const int32_t sp = m.row_spring[e];
    Real dvx = 0, dvy = 0, dvz = 0;
    if constexpr (kDamping) {
      dvx = ((s.x[j] - s.px[j]) - (xi - s.px[i])) * inv_dt;
      dvy = ((s.y[j] - s.py[j]) - (yi - s.py[i])) * inv_dt;
      dvz = ((s.z[j] - s.pz[j]) - (zi - s.pz[i])) * inv_dt;
    }
    add_spring<kDamping, kNormals>(s.x[j] - xi, s.y[j] - yi, s.z[j] - zi, dvx, dvy, dvz, m.stiffness[sp], m.rest_length[sp],
                         m.damping[sp], static_cast<Real>(m.alive[sp] != 0), sum);
  }
  return sum;
}

}  // namespace ctsurg::sim
