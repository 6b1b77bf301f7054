// Per-node kernels of the FEM explicit dynamics (host and device): the central-difference update of
// the paper's eq. 12 with a lumped (diagonal) mass matrix and Rayleigh mass damping D = lambda_d M.
// Row i of eq. 12 divided by m_i:
//
//   (1/dt^2 + lambda_d/(2 dt)) u+ = (f_i + f_ext,i)/m_i + g + 2/dt^2 u - (1/dt^2 - lambda_d/(2 dt)) u-
//   u+ = [dt^2 ((f + f_ext)/m + g) + 2 u - (1 - c) u-] / (1 + c),    c = lambda_d dt / 2
//
// f = internal elastic force gathered from the element pass (fem_forces_impl.h). Held nodes (inverse
// mass 0: fixed, grabbed, or used by no tet) keep u+ = u. Displacements #N x 3 row-major, mm.
#pragma once

#include "ctsurg/sim/fem/kernels/fem_forces_impl.h"

namespace ctsurg::sim {

struct FemNodeView {
  const int32_t* offsets;  // #N + 1 CSR row starts
  const int32_t* corners;  // 4 e + corner entries
  const Real* u;           // #N x 3 displacements now, mm
  const Real* u_prev;      // #N x 3 one step earlier
  Real* u_next;            // #N x 3 one step later (written)
  const Real* inv_mass;    // #N 1/g, 0 = held
  const Real* external;    // #N x 3 uN, or null
  int32_t count;           // #N
};

struct FemStepConstants {
  Real dt2_over;    // dt^2 / (1 + c), s^2
  Real two_over;    // 2 / (1 + c)
  Real prev_ratio;  // (1 - c) / (1 + c)
  Real gx, gy, gz;  // gravity, mm/s^2
};

struct FemSphereView {
  double cx, cy, cz, radius;  // mm
};

// Node i's next displacement; returns false when it is not finite.
CTSURG_HD inline bool fem_node_update(const FemNodeView& v, const FemStepConstants& k, const Real* corner_forces, int32_t i) {
  const Real* u = v.u + 3 * i;
  Real* un = v.u_next + 3 * i;
  const Real w = v.inv_mass[i];
  if (w == Real(0)) {
    un[0] = u[0];
    un[1] = u[1];
    un[2] = u[2];
    return true;
  }
  Real f[3];
  fem_gather_node_force(v.offsets, v.corners, corner_forces, i, f);
  if (v.external) {
    f[0] += v.external[3 * i];
    f[1] += v.external[3 * i + 1];
    f[2] += v.external[3 * i + 2];
  }
  const Real* up = v.u_prev + 3 * i;
  const Real g[3] = {k.gx, k.gy, k.gz};
  bool finite = true;
  CTSURG_UNROLL
  for (int c = 0; c < 3; ++c) {
    un[c] = k.dt2_over * (f[c] * w + g[c]) + k.two_over * u[c] - k.prev_ratio * up[c];
    finite = finite && isfinite(un[c]);
  }
  return finite;
}

// Sphere contact for node i (rest position from `rest`, #N x 3 double): a free node inside the sphere
// moves to the surface along the ray from the centre (a node at the centre moves along +x). Returns
// whether it moved.
CTSURG_HD inline bool fem_sphere_contact_node(Real* u, const double* rest, const Real* inv_mass, const FemSphereView& s,
                                              int32_t i) {
  if (inv_mass[i] == Real(0)) return false;
  const double p[3] = {rest[3 * i] + u[3 * i], rest[3 * i + 1] + u[3 * i + 1], rest[3 * i + 2] + u[3 * i + 2]};
  const double d[3] = {p[0] - s.cx, p[1] - s.cy, p[2] - s.cz};
  const double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
  if (!(r2 < s.radius * s.radius)) return false;
  const double r = sqrt(r2);
  double n[3] = {1, 0, 0};
  if (r > 1e-12 * s.radius) {
    n[0] = d[0] / r;
    n[1] = d[1] / r;
    n[2] = d[2] / r;
  }
  CTSURG_UNROLL
  for (int c = 0; c < 3; ++c) u[3 * i + c] = static_cast<Real>((c == 0 ? s.cx : c == 1 ? s.cy : s.cz) + s.radius * n[c] - rest[3 * i + c]);
  return true;
}

}  // namespace ctsurg::sim
