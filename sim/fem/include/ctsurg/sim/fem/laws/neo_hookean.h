// Compressible Neo-Hookean (Bonet and Wood 2008, "Nonlinear continuum mechanics for finite element
// analysis", eq. 6.28):
//   psi = mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2,   P = mu (F - F^-T) + lambda ln(J) F^-T,
//   A = mu d_rj d_cd + (mu - lambda ln J) G_rd G_jc + lambda G_rc G_jd,   G = F^-T.
// Rotation invariant, infinite energy as J -> 0 (needs J > 0); the tangent is indefinite far from rest.
// Anchor: SOFA's hyperelastic material/NeoHookean.h.
#pragma once

#include "ctsurg/sim/fem/kernels/fem_matrix3_impl.h"
#include "ctsurg/sim/fem/laws/fem_law_types.h"

namespace ctsurg::sim {

struct NeoHookeanLaw {
  static constexpr bool kNeedsPositiveJ = true;
  static constexpr bool kIndefiniteTangent = true;
  static constexpr FemLawInfo kInfo{"neo_hookean", "compressible Neo-Hookean (Bonet and Wood 2008 eq. 6.28)", 0,
                                    {nullptr, nullptr}, {0, 0}};

  template <class T>
  CTSURG_HD static T energy_density(const FemLawParameters<T>& k, const T* F) {
    const T J = det3(F);
    T i1 = T(0);
    CTSURG_UNROLL
    for (int i = 0; i < 9; ++i) i1 += F[i] * F[i];
    const T lj = kernel_log(J);
    return T(0.5) * k.mu * (i1 - T(3)) - k.mu * lj + T(0.5) * k.lambda * lj * lj;
  }

  template <class T>
  CTSURG_HD static void first_piola(const FemLawParameters<T>& k, const T* F, T J, T* P) {
    T C[9];
    cofactor3(F, C);  // F^-T = C / J
    const T inv_j = T(1) / J;
    const T a = (k.lambda * kernel_log(J) - k.mu) * inv_j;
    CTSURG_UNROLL
    for (int i = 0; i < 9; ++i) P[i] = k.mu * F[i] + a * C[i];
  }

  template <class T>
  CTSURG_HD static void tangent(const FemLawParameters<T>& k, const T* F, T J, T* A) {
    const T mu = k.mu, lambda = k.lambda;
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
  }
};

}  // namespace ctsurg::sim
