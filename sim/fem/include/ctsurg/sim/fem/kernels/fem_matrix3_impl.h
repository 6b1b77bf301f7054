// 3x3 matrix helpers of the FEM's material laws and element kernels (host and device): determinant,
// cofactor, logarithm in the kernels' precision, and the rotation of the polar decomposition with the
// corotated strain (the corotational law). Matrices 3x3 row-major. No std containers, exceptions or
// virtual calls (see real.h).
#pragma once

#include "ctsurg/sim/base/kernels/kernel_support.h"

#include <math.h>
#include <stdint.h>

namespace ctsurg::sim {

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

}  // namespace ctsurg::sim
