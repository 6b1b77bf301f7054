// St. Venant-Kirchhoff, Huang et al., the FEM paper, eq. 6-8: the linear law on the Green-Lagrange strain,
//   E = (F^T F - I)/2,   S = 2 mu E + lambda tr(E) I,   P = F S,   psi = mu |E|^2 + lambda/2 tr(E)^2,
//   A = d_rj S_dc + mu F_rd F_jc + mu (F F^T)_rj d_cd + lambda F_rc F_jd.
// Rotation invariant; softens and loses definiteness under compression (indefinite tangent).
#pragma once

#include "ctsurg/sim/fem/kernels/fem_matrix3_impl.h"
#include "ctsurg/sim/fem/laws/fem_law_types.h"

namespace ctsurg::sim {

struct StvkLaw {
  static constexpr bool kNeedsPositiveJ = false;
  static constexpr bool kIndefiniteTangent = true;
  static constexpr FemLawInfo kInfo{"stvk", "St. Venant-Kirchhoff (FEM paper eq. 6-8)", 0, {nullptr, nullptr}, {0, 0}};

  template <class T>
  CTSURG_HD static T energy_density(const FemLawParameters<T>& k, const T* F) {
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
    return k.mu * ee + T(0.5) * k.lambda * tr * tr;
  }

  template <class T>
  CTSURG_HD static void first_piola(const FemLawParameters<T>& k, const T* F, T J, T* P) {
    T S[9];
    CTSURG_UNROLL
    for (int r = 0; r < 3; ++r)
      CTSURG_UNROLL
      for (int c = 0; c < 3; ++c)
        S[r * 3 + c] = T(0.5) * (F[0 * 3 + r] * F[0 * 3 + c] + F[1 * 3 + r] * F[1 * 3 + c] + F[2 * 3 + r] * F[2 * 3 + c] -
                                 (r == c ? T(1) : T(0)));
    const T tr = S[0] + S[4] + S[8];
    CTSURG_UNROLL
    for (int i = 0; i < 9; ++i) S[i] *= T(2) * k.mu;
    S[0] += k.lambda * tr;
    S[4] += k.lambda * tr;
    S[8] += k.lambda * tr;
    CTSURG_UNROLL
    for (int r = 0; r < 3; ++r)
      CTSURG_UNROLL
      for (int c = 0; c < 3; ++c)
        P[r * 3 + c] = F[r * 3 + 0] * S[0 * 3 + c] + F[r * 3 + 1] * S[1 * 3 + c] + F[r * 3 + 2] * S[2 * 3 + c];
  }

  template <class T>
  CTSURG_HD static void tangent(const FemLawParameters<T>& k, const T* F, T J, T* A) {
    const T mu = k.mu, lambda = k.lambda;
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
  }
};

}  // namespace ctsurg::sim
