// Per-element kernels of the linear (4-node) tetrahedron, total Lagrangian, written once for the host
// and a later CUDA build (STYLE.md rule 5): deformation gradient, first Piola-Kirchhoff stress of the
// three materials (fem_material.h), nodal forces, strain energy and the 12x12 tangent stiffness.
// Templated on the scalar: float (Real) for explicit dynamics, double for the static solver.
//
// Notation. Rest corners X0..X3, Dm = [X1-X0, X2-X0, X3-X0] (columns), B = Dm^-1 (row-major). With
// corner displacements u0..u3, F = I + Du B, Du = [u1-u0, u2-u0, u3-u0]: computed from displacements,
// not positions, so that a small strain keeps its digits in float. The shape-function gradients are
// g_a = row a-1 of B (a = 1..3), g_0 = -(g_1 + g_2 + g_3). Energy V psi(F), V = |det Dm| / 6; the force
// on corner a is f_a = -V P g_a (uN; P in Pa = g/(mm s^2), V in mm^3, g in 1/mm). The tangent
// stiffness K_ab = V dP[e_j (x) g_b] g_a is the Hessian of the element energy (symmetric).
//
// No std containers, exceptions or virtual calls (see real.h). Matrices 3x3 row-major.
#pragma once

#include "ctsurg/sim/base/kernels/kernel_support.h"

#include <math.h>
#include <stdint.h>

namespace ctsurg::sim {

// Material model ids (FemMaterialModel's values) as plain ints for the kernels.
constexpr int32_t kFemLinear = 0;
constexpr int32_t kFemStvk = 1;
constexpr int32_t kFemNeoHookean = 2;

CTSURG_HD inline float kernel_log(float v) { return logf(v); }
CTSURG_HD inline double kernel_log(double v) { return log(v); }

template <class T>
CTSURG_HD inline T det3(const T* a) {
  return a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) + a[2] * (a[3] * a[7] - a[4] * a[6]);
}

// The cofactor matrix of a (cof = det(a) a^-T), row-major.
template <class T>
CTSURG_HD inline void cofactor3(const T* a, T* c) {
  c[0] = a[4] * a[8] - a[5] * a[7];
  c[1] = a[5] * a[6] - a[3] * a[8];
  c[2] = a[3] * a[7] - a[4] * a[6];
  c[3] = a[2] * a[7] - a[1] * a[8];
  c[4] = a[0] * a[8] - a[2] * a[6];
  c[5] = a[1] * a[6] - a[0] * a[7];
  c[6] = a[1] * a[5] - a[2] * a[4];
  c[7] = a[2] * a[3] - a[0] * a[5];
  c[8] = a[0] * a[4] - a[1] * a[3];
}

// F = I + Du B. u: 12 corner displacements (corner-major, xyz), B: Dm^-1 row-major.
template <class T>
CTSURG_HD inline void fem_deformation_gradient(const T* u, const T* B, T* F) {
  T du[9];  // du[r*3+k] = u_{k+1,r} - u_{0,r}
  CTSURG_UNROLL
  for (int r = 0; r < 3; ++r)
    CTSURG_UNROLL
    for (int k = 0; k < 3; ++k) du[r * 3 + k] = u[(k + 1) * 3 + r] - u[r];
  CTSURG_UNROLL
  for (int r = 0; r < 3; ++r)
    CTSURG_UNROLL
    for (int c = 0; c < 3; ++c)
      F[r * 3 + c] = (r == c ? T(1) : T(0)) + du[r * 3 + 0] * B[0 * 3 + c] + du[r * 3 + 1] * B[1 * 3 + c] +
                     du[r * 3 + 2] * B[2 * 3 + c];
}

// P(F) for `model`; returns false and P = 0 when det F <= 0 (inverted: the caller reports it).
template <class T>
CTSURG_HD inline bool fem_first_piola(int32_t model, T mu, T lambda, const T* F, T* P) {
  const T J = det3(F);
  if (!(J > T(0))) {
    CTSURG_UNROLL
    for (int i = 0; i < 9; ++i) P[i] = T(0);
    return false;
  }
  if (model == kFemLinear) {
    const T tr = F[0] + F[4] + F[8] - T(3);
    CTSURG_UNROLL
    for (int r = 0; r < 3; ++r)
      CTSURG_UNROLL
      for (int c = 0; c < 3; ++c) {
        const T eps = T(0.5) * (F[r * 3 + c] + F[c * 3 + r]) - (r == c ? T(1) : T(0));
        P[r * 3 + c] = T(2) * mu * eps + (r == c ? lambda * tr : T(0));
      }
  } else if (model == kFemStvk) {
    T S[9];
    CTSURG_UNROLL
    for (int r = 0; r < 3; ++r)
      CTSURG_UNROLL
      for (int c = 0; c < 3; ++c)
        S[r * 3 + c] = T(0.5) * (F[0 * 3 + r] * F[0 * 3 + c] + F[1 * 3 + r] * F[1 * 3 + c] + F[2 * 3 + r] * F[2 * 3 + c] -
                                 (r == c ? T(1) : T(0)));
    const T tr = S[0] + S[4] + S[8];
    CTSURG_UNROLL
    for (int i = 0; i < 9; ++i) S[i] *= T(2) * mu;
    S[0] += lambda * tr;
    S[4] += lambda * tr;
    S[8] += lambda * tr;
    CTSURG_UNROLL
    for (int r = 0; r < 3; ++r)
      CTSURG_UNROLL
      for (int c = 0; c < 3; ++c)
        P[r * 3 + c] = F[r * 3 + 0] * S[0 * 3 + c] + F[r * 3 + 1] * S[1 * 3 + c] + F[r * 3 + 2] * S[2 * 3 + c];
  } else {
    T C[9];
    cofactor3(F, C);  // F^-T = C / J
    const T inv_j = T(1) / J;
    const T a = (lambda * kernel_log(J) - mu) * inv_j;
    CTSURG_UNROLL
    for (int i = 0; i < 9; ++i) P[i] = mu * F[i] + a * C[i];
  }
  return true;
}

// Strain energy density psi(F), Pa; for neo_hookean with det F <= 0 returns a huge value (1e30).
template <class T>
CTSURG_HD inline T fem_energy_density(int32_t model, T mu, T lambda, const T* F) {
  if (model == kFemLinear) {
    T ee = T(0);
    CTSURG_UNROLL
    for (int r = 0; r < 3; ++r)
      CTSURG_UNROLL
      for (int c = 0; c < 3; ++c) {
        const T eps = T(0.5) * (F[r * 3 + c] + F[c * 3 + r]) - (r == c ? T(1) : T(0));
        ee += eps * eps;
      }
    const T tr = F[0] + F[4] + F[8] - T(3);
    return mu * ee + T(0.5) * lambda * tr * tr;
  }
  if (model == kFemStvk) {
    T ee = T(0), tr = T(0);
    CTSURG_UNROLL
    for (int r = 0; r < 3; ++r)
      CTSURG_UNROLL
      for (int c = 0; c < 3; ++c) {
        const T e = T(0.5) * (F[0 * 3 + r] * F[0 * 3 + c] + F[1 * 3 + r] * F[1 * 3 + c] + F[2 * 3 + r] * F[2 * 3 + c] -
                              (r == c ? T(1) : T(0)));
        ee += e * e;
        if (r == c) tr += e;
      }
    return mu * ee + T(0.5) * lambda * tr * tr;
  }
  const T J = det3(F);
  if (!(J > T(0))) return T(1e30);
  T i1 = T(0);
  CTSURG_UNROLL
  for (int i = 0; i < 9; ++i) i1 += F[i] * F[i];
  const T lj = kernel_log(J);
  return T(0.5) * mu * (i1 - T(3)) - mu * lj + T(0.5) * lambda * lj * lj;
}

// Shape-function gradients g[a*3+c], a = 0..3, from B.
template <class T>
CTSURG_HD inline void fem_shape_gradients(const T* B, T* g) {
  CTSURG_UNROLL
  for (int c = 0; c < 3; ++c) {
    g[3 + c] = B[0 * 3 + c];
    g[6 + c] = B[1 * 3 + c];
    g[9 + c] = B[2 * 3 + c];
    g[c] = -(B[0 * 3 + c] + B[1 * 3 + c] + B[2 * 3 + c]);
  }
}

// Corner forces f[a*3+r] = -V P g_a (uN) from P (Pa), B and V (mm^3).
template <class T>
CTSURG_HD inline void fem_corner_forces(const T* P, const T* B, T V, T* f) {
  CTSURG_UNROLL
  for (int r = 0; r < 3; ++r) {
    T s = T(0);
    CTSURG_UNROLL
    for (int a = 1; a < 4; ++a) {
      const T fa = -V * (P[r * 3 + 0] * B[(a - 1) * 3 + 0] + P[r * 3 + 1] * B[(a - 1) * 3 + 1] +
                         P[r * 3 + 2] * B[(a - 1) * 3 + 2]);
      f[a * 3 + r] = fa;
      s += fa;
    }
    f[r] = -s;  // the forces of an element sum to zero exactly
  }
}

// The element's forces from its corner displacements: f (12, uN). Returns false for an inverted
// element (det F <= 0), whose forces are then zero.
template <class T>
CTSURG_HD inline bool fem_element_forces(int32_t model, T mu, T lambda, const T* u, const T* B, T V, T* f) {
  T F[9], P[9];
  fem_deformation_gradient(u, B, F);
  const bool ok = fem_first_piola(model, mu, lambda, F, P);
  fem_corner_forces(P, B, V, f);
  return ok;
}

// dP for a perturbation dF at F (the material's tangent), row-major.
template <class T>
CTSURG_HD inline void fem_stress_differential(int32_t model, T mu, T lambda, const T* F, const T* dF, T* dP) {
  if (model == kFemLinear) {
    const T tr = dF[0] + dF[4] + dF[8];
    CTSURG_UNROLL
    for (int r = 0; r < 3; ++r)
      CTSURG_UNROLL
      for (int c = 0; c < 3; ++c) dP[r * 3 + c] = mu * (dF[r * 3 + c] + dF[c * 3 + r]) + (r == c ? lambda * tr : T(0));
  } else if (model == kFemStvk) {
    T S[9], dS[9];
    T trE = T(0), trdE = T(0);
    CTSURG_UNROLL
    for (int r = 0; r < 3; ++r)
      CTSURG_UNROLL
      for (int c = 0; c < 3; ++c) {
        T ftf = T(0), sym = T(0);
        CTSURG_UNROLL
        for (int k = 0; k < 3; ++k) {
          ftf += F[k * 3 + r] * F[k * 3 + c];
          sym += dF[k * 3 + r] * F[k * 3 + c] + F[k * 3 + r] * dF[k * 3 + c];
        }
        S[r * 3 + c] = T(0.5) * (ftf - (r == c ? T(1) : T(0)));
        dS[r * 3 + c] = T(0.5) * sym;
        if (r == c) {
          trE += S[r * 3 + c];
          trdE += dS[r * 3 + c];
        }
      }
    CTSURG_UNROLL
    for (int i = 0; i < 9; ++i) {
      S[i] *= T(2) * mu;
      dS[i] *= T(2) * mu;
    }
    CTSURG_UNROLL
    for (int d = 0; d < 3; ++d) {
      S[d * 4] += lambda * trE;
      dS[d * 4] += lambda * trdE;
    }
    CTSURG_UNROLL
    for (int r = 0; r < 3; ++r)
      CTSURG_UNROLL
      for (int c = 0; c < 3; ++c) {
        T v = T(0);
        CTSURG_UNROLL
        for (int k = 0; k < 3; ++k) v += dF[r * 3 + k] * S[k * 3 + c] + F[r * 3 + k] * dS[k * 3 + c];
        dP[r * 3 + c] = v;
      }
  } else {
    // dP = mu dF + (mu - lambda ln J) F^-T dF^T F^-T + lambda tr(F^-1 dF) F^-T
    const T J = det3(F);
    T G[9];  // F^-T
    cofactor3(F, G);
    CTSURG_UNROLL
    for (int i = 0; i < 9; ++i) G[i] /= J;
    T tr = T(0);  // tr(F^-1 dF) = sum_rc F^-T_rc dF_rc
    CTSURG_UNROLL
    for (int i = 0; i < 9; ++i) tr += G[i] * dF[i];
    T M[9];  // dF^T G
    CTSURG_UNROLL
    for (int r = 0; r < 3; ++r)
      CTSURG_UNROLL
      for (int c = 0; c < 3; ++c) M[r * 3 + c] = dF[0 * 3 + r] * G[0 * 3 + c] + dF[1 * 3 + r] * G[1 * 3 + c] + dF[2 * 3 + r] * G[2 * 3 + c];
    const T a = mu - lambda * kernel_log(J);
    CTSURG_UNROLL
    for (int r = 0; r < 3; ++r)
      CTSURG_UNROLL
      for (int c = 0; c < 3; ++c) {
        const T gm = G[r * 3 + 0] * M[0 * 3 + c] + G[r * 3 + 1] * M[1 * 3 + c] + G[r * 3 + 2] * M[2 * 3 + c];
        dP[r * 3 + c] = mu * dF[r * 3 + c] + a * gm + lambda * tr * G[r * 3 + c];
      }
  }
}

// The 12x12 tangent stiffness K (row-major, K[(a*3+r)*12 + b*3+j] = d(-f_{a,r}) / du_{b,j}, uN/mm) at the
// corner displacements u. Returns false for an inverted element (K = 0).
template <class T>
CTSURG_HD inline bool fem_element_stiffness(int32_t model, T mu, T lambda, const T* u, const T* B, T V, T* K) {
  T F[9], g[12];
  fem_deformation_gradient(u, B, F);
  if (!(det3(F) > T(0))) {
    for (int i = 0; i < 144; ++i) K[i] = T(0);
    return false;
  }
  fem_shape_gradients(B, g);
  for (int b = 0; b < 4; ++b)
    for (int j = 0; j < 3; ++j) {
      T dF[9], dP[9];
      CTSURG_UNROLL
      for (int r = 0; r < 3; ++r)
        CTSURG_UNROLL
        for (int c = 0; c < 3; ++c) dF[r * 3 + c] = r == j ? g[b * 3 + c] : T(0);
      fem_stress_differential(model, mu, lambda, F, dF, dP);
      const int col = b * 3 + j;
      for (int a = 0; a < 4; ++a)
        CTSURG_UNROLL
        for (int r = 0; r < 3; ++r)
          K[(a * 3 + r) * 12 + col] =
              V * (dP[r * 3 + 0] * g[a * 3 + 0] + dP[r * 3 + 1] * g[a * 3 + 1] + dP[r * 3 + 2] * g[a * 3 + 2]);
    }
  return true;
}

}  // namespace ctsurg::sim
