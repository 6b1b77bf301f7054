// Per-element kernels of the linear (4-node) tetrahedron, total Lagrangian, written once for the host
// and the CUDA build (STYLE.md rule 5): deformation gradient, first Piola-Kirchhoff stress of the four
// materials (fem_material.h), nodal forces, strain energy, the material tangent dP/dF and the 12x12
// tangent stiffness.
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
constexpr int32_t kFemCorotational = 3;

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

// The rotation R of the polar decomposition F = R S (S symmetric positive definite), for det F > 0:
// the scaled Newton iteration X <- (g X + X^-T / g) / 2, g = (|X^-1|_F / |X|_F)^(1/2) (Higham 1986,
// "Computing the polar decomposition", section 3), from X = F; quadratic convergence, about 5 steps
// from a 90-degree rotation with 2x stretch to double precision. Returns false (R = I) when det F <= 0.
template <class T>
CTSURG_HD inline bool fem_polar_rotation(const T* F, T* R) {
  T X[9];
  CTSURG_UNROLL
  for (int i = 0; i < 9; ++i) X[i] = F[i];
  if (!(det3(X) > T(0))) {
    CTSURG_UNROLL
    for (int i = 0; i < 9; ++i) R[i] = (i % 4 == 0) ? T(1) : T(0);
    return false;
  }
  const T tolerance = sizeof(T) == 4 ? T(1e-6) : T(1e-13);
  for (int it = 0; it < 20; ++it) {
    T C[9];
    cofactor3(X, C);  // X^-T = C / det X
    const T d = det3(X);
    T nx = T(0), ni = T(0);
    CTSURG_UNROLL
    for (int i = 0; i < 9; ++i) {
      nx += X[i] * X[i];
      ni += C[i] * C[i];
    }
    ni /= d * d;
    const T g = kernel_sqrt(kernel_sqrt(ni / nx));
    T change = T(0);
    CTSURG_UNROLL
    for (int i = 0; i < 9; ++i) {
      const T next = T(0.5) * (g * X[i] + C[i] / (g * d));
      change += (next - X[i]) * (next - X[i]);
      X[i] = next;
    }
    if (change <= tolerance * tolerance * T(3)) break;
  }
  CTSURG_UNROLL
  for (int i = 0; i < 9; ++i) R[i] = X[i];
  return true;
}

// The corotational (Mueller and Gross 2004, "Interactive virtual materials"; SOFA's default
// tetrahedral model) small strain: with F = R S, eps = S - I, taken as sym(R^T F) - I.
template <class T>
CTSURG_HD inline void fem_corotated_strain(const T* F, const T* R, T* eps) {
  CTSURG_UNROLL
  for (int r = 0; r < 3; ++r)
    CTSURG_UNROLL
    for (int c = 0; c < 3; ++c) {
      const T rf = R[0 * 3 + r] * F[0 * 3 + c] + R[1 * 3 + r] * F[1 * 3 + c] + R[2 * 3 + r] * F[2 * 3 + c];
      const T fr = R[0 * 3 + c] * F[0 * 3 + r] + R[1 * 3 + c] * F[1 * 3 + r] + R[2 * 3 + c] * F[2 * 3 + r];
      eps[r * 3 + c] = T(0.5) * (rf + fr) - (r == c ? T(1) : T(0));
    }
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
  } else if (model == kFemCorotational) {
    // P = R (2 mu eps + lambda tr(eps) I): the linear stress of the rotated-back strain, rotated.
    T R[9], eps[9];
    fem_polar_rotation(F, R);
    fem_corotated_strain(F, R, eps);
    const T tr = eps[0] + eps[4] + eps[8];
    T sigma[9];
    CTSURG_UNROLL
    for (int i = 0; i < 9; ++i) sigma[i] = T(2) * mu * eps[i] + (i % 4 == 0 ? lambda * tr : T(0));
    CTSURG_UNROLL
    for (int r = 0; r < 3; ++r)
      CTSURG_UNROLL
      for (int c = 0; c < 3; ++c)
        P[r * 3 + c] = R[r * 3 + 0] * sigma[0 * 3 + c] + R[r * 3 + 1] * sigma[1 * 3 + c] + R[r * 3 + 2] * sigma[2 * 3 + c];
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
  if (model == kFemCorotational) {
    // psi = mu |eps|^2 + lambda/2 tr(eps)^2 of the corotated strain: rotation invariant.
    if (!(det3(F) > T(0))) return T(1e30);
    T R[9], eps[9];
    fem_polar_rotation(F, R);
    fem_corotated_strain(F, R, eps);
    T ee = T(0);
    CTSURG_UNROLL
    for (int i = 0; i < 9; ++i) ee += eps[i] * eps[i];
    const T tr = eps[0] + eps[4] + eps[8];
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

// The material tangent A = dP/dF at F (9 x 9, row-major over the pairs (r c) and (j d):
// A[(3 r + c) 9 + 3 j + d] = dP_rc / dF_jd), symmetric for the hyperelastic laws:
//   linear          mu (d_rj d_cd + d_rd d_cj) + lambda d_rc d_jd
//   stvk            d_rj S_dc + mu F_rd F_jc + mu (F F^T)_rj d_cd + lambda F_rc F_jd
//   neo_hookean     mu d_rj d_cd + (mu - lambda ln J) G_rd G_jc + lambda G_rc G_jd,  G = F^-T
//   corotational    the linear tangent rotated by F's R on both sides (R K0 R^T, the "warped
//                   stiffness" of Mueller and Gross 2004; the derivative of R is left out, as SOFA does:
//                   positive semi-definite always, a quasi-Newton tangent)
// Returns false for det F <= 0 (A = 0).
template <class T>
CTSURG_HD inline bool fem_material_tangent(int32_t model, T mu, T lambda, const T* F, T* A) {
  const T J = det3(F);
  if (!(J > T(0))) {
    for (int i = 0; i < 81; ++i) A[i] = T(0);
    return false;
  }
  if (model == kFemLinear || model == kFemCorotational) {
    T L[81];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        for (int j = 0; j < 3; ++j)
          for (int d = 0; d < 3; ++d)
            L[(3 * r + c) * 9 + 3 * j + d] = mu * (T(r == j && c == d) + T(r == d && c == j)) + lambda * T(r == c && j == d);
    if (model == kFemLinear) {
      for (int i = 0; i < 81; ++i) A[i] = L[i];
      return true;
    }
    T R[9];
    fem_polar_rotation(F, R);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        for (int j = 0; j < 3; ++j)
          for (int d = 0; d < 3; ++d) {
            T v = T(0);
            for (int p = 0; p < 3; ++p)
              for (int q = 0; q < 3; ++q) v += R[r * 3 + p] * L[(3 * p + c) * 9 + 3 * q + d] * R[j * 3 + q];
            A[(3 * r + c) * 9 + 3 * j + d] = v;
          }
    return true;
  }
  if (model == kFemStvk) {
    T S[9], FFt[9];
    T trE = T(0);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) {
        S[r * 3 + c] = T(0.5) * (F[0 * 3 + r] * F[0 * 3 + c] + F[1 * 3 + r] * F[1 * 3 + c] + F[2 * 3 + r] * F[2 * 3 + c] -
                                 (r == c ? T(1) : T(0)));
        FFt[r * 3 + c] = F[r * 3 + 0] * F[c * 3 + 0] + F[r * 3 + 1] * F[c * 3 + 1] + F[r * 3 + 2] * F[c * 3 + 2];
      }
    trE = S[0] + S[4] + S[8];
    for (int i = 0; i < 9; ++i) S[i] *= T(2) * mu;
    S[0] += lambda * trE;
    S[4] += lambda * trE;
    S[8] += lambda * trE;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        for (int j = 0; j < 3; ++j)
          for (int d = 0; d < 3; ++d)
            A[(3 * r + c) * 9 + 3 * j + d] = (r == j ? S[d * 3 + c] : T(0)) + mu * F[r * 3 + d] * F[j * 3 + c] +
                                             (c == d ? mu * FFt[r * 3 + j] : T(0)) + lambda * F[r * 3 + c] * F[j * 3 + d];
    return true;
  }
  T G[9];
  cofactor3(F, G);
  for (int i = 0; i < 9; ++i) G[i] /= J;
  const T a = mu - lambda * kernel_log(J);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      for (int j = 0; j < 3; ++j)
        for (int d = 0; d < 3; ++d)
          A[(3 * r + c) * 9 + 3 * j + d] = (r == j && c == d ? mu : T(0)) + a * G[r * 3 + d] * G[j * 3 + c] +
                                           lambda * G[r * 3 + c] * G[j * 3 + d];
  return true;
}

// K = V G^T A G: K[(3 a + r) 12 + 3 b + j] = V sum_cd g_ac A[(3 r + c) 9 + 3 j + d] g_bd, from the
// material tangent A (9 x 9) and the shape-function gradients g (4 x 3). uN/mm.
template <class T>
CTSURG_HD inline void fem_stiffness_from_tangent(const T* A, const T* g, T V, T* K) {
  for (int r = 0; r < 3; ++r)
    for (int j = 0; j < 3; ++j) {
      T Ag[12];  // Ag[c 4 + b] = sum_d A[(r c), (j d)] g_bd
      for (int c = 0; c < 3; ++c)
        for (int b = 0; b < 4; ++b)
          Ag[c * 4 + b] = A[(3 * r + c) * 9 + 3 * j + 0] * g[b * 3 + 0] + A[(3 * r + c) * 9 + 3 * j + 1] * g[b * 3 + 1] +
                          A[(3 * r + c) * 9 + 3 * j + 2] * g[b * 3 + 2];
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b)
          K[(3 * a + r) * 12 + 3 * b + j] = V * (g[a * 3 + 0] * Ag[0 * 4 + b] + g[a * 3 + 1] * Ag[1 * 4 + b] + g[a * 3 + 2] * Ag[2 * 4 + b]);
    }
}

// The 12x12 tangent stiffness K (row-major, K[(a*3+r)*12 + b*3+j] = d(-f_{a,r}) / du_{b,j}, uN/mm) at the
// corner displacements u: the Hessian of the element's energy (corotational: the warped stiffness).
// Returns false for an inverted element (K = 0).
template <class T>
CTSURG_HD inline bool fem_element_stiffness(int32_t model, T mu, T lambda, const T* u, const T* B, T V, T* K) {
  T F[9], g[12], A[81];
  fem_deformation_gradient(u, B, F);
  if (!fem_material_tangent(model, mu, lambda, F, A)) {
    for (int i = 0; i < 144; ++i) K[i] = T(0);
    return false;
  }
  fem_shape_gradients(B, g);
  fem_stiffness_from_tangent(A, g, V, K);
  return true;
}

}  // namespace ctsurg::sim
