// Linear (small-strain) elasticity, Huang et al., the FEM paper of /work/shared/seeds, eq. 2-5:
//   eps = (F + F^T)/2 - I,   P = sigma = 2 mu eps + lambda tr(eps) I,
//   psi = mu |eps|^2 + lambda/2 tr(eps)^2,   A = mu (d_rj d_cd + d_rd d_cj) + lambda d_rc d_jd.
// Its tangent does not depend on F: the static solvers factorise it once. Not rotation invariant.
#pragma once

#include "ctsurg/sim/fem/kernels/fem_matrix3_impl.h"
#include "ctsurg/sim/fem/laws/fem_law_types.h"

namespace ctsurg::sim {

// The linear law's tangent (9 x 9), shared with the corotational law, which rotates it.
template <class T>
CTSURG_HD inline void fem_linear_tangent(T mu, T lambda, T* L) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      for (int j = 0; j < 3; ++j)
        for (int d = 0; d < 3; ++d)
          L[(3 * r + c) * 9 + 3 * j + d] = mu * (T(r == j && c == d) + T(r == d && c == j)) + lambda * T(r == c && j == d);
}

struct LinearLaw {
  static constexpr bool kNeedsPositiveJ = false;
  static constexpr bool kIndefiniteTangent = false;
  static constexpr FemLawInfo kInfo{"linear", "small-strain linear elasticity (FEM paper eq. 2-5)", 0, {nullptr, nullptr}, {0, 0}};

  template <class T>
  CTSURG_HD static T energy_density(const FemLawParameters<T>& k, const T* F) {
    T ee = T(0);
    CTSURG_UNROLL
    for (int r = 0; r < 3; ++r)
      CTSURG_UNROLL
      for (int c = 0; c < 3; ++c) {
        const T eps = T(0.5) * (F[r * 3 + c] + F[c * 3 + r]) - (r == c ? T(1) : T(0));
        ee += eps * eps;
      }
    const T tr = F[0] + F[4] + F[8] - T(3);
    return k.mu * ee + T(0.5) * k.lambda * tr * tr;
  }

  template <class T>
  CTSURG_HD static void first_piola(const FemLawParameters<T>& k, const T* F, T J, T* P) {
    const T tr = F[0] + F[4] + F[8] - T(3);
    CTSURG_UNROLL
    for (int r = 0; r < 3; ++r)
      CTSURG_UNROLL
      for (int c = 0; c < 3; ++c) {
        const T eps = T(0.5) * (F[r * 3 + c] + F[c * 3 + r]) - (r == c ? T(1) : T(0));
        P[r * 3 + c] = T(2) * k.mu * eps + (r == c ? k.lambda * tr : T(0));
      }
  }

  template <class T>
  CTSURG_HD static void tangent(const FemLawParameters<T>& k, const T* F, T J, T* A) {
    fem_linear_tangent(k.mu, k.lambda, A);
  }
};

}  // namespace ctsurg::sim
