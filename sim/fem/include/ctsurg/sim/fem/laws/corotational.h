// Corotational linear elasticity (Mueller and Gross 2004, "Interactive virtual materials"; SOFA's
// default tetrahedral law): with F = R S (polar decomposition), eps = S - I,
//   P = R (2 mu eps + lambda tr(eps) I),   psi = mu |eps|^2 + lambda/2 tr(eps)^2,
// the linear law in each element's rotated frame, so a rigid rotation costs nothing, at the price of
// linear behaviour in stretch. Tangent: the linear one rotated by R on both sides (R K0 R^T, the
// "warped stiffness"; the derivative of R is left out, as SOFA does: positive semi-definite always, a
// quasi-Newton tangent). R is undefined for det F <= 0, so the energy is infinite there.
#pragma once

#include "ctsurg/sim/fem/kernels/fem_matrix3_impl.h"
#include "ctsurg/sim/fem/laws/fem_law_types.h"
#include "ctsurg/sim/fem/laws/linear.h"

namespace ctsurg::sim {

struct CorotationalLaw {
  static constexpr bool kNeedsPositiveJ = true;
  static constexpr bool kIndefiniteTangent = false;
  static constexpr FemLawInfo kInfo{"corotational", "corotational linear elasticity (Mueller and Gross 2004)", 0,
                                    {nullptr, nullptr}, {0, 0}};

  template <class T>
  CTSURG_HD static T energy_density(const FemLawParameters<T>& k, const T* F) {
    T R[9], eps[9];
    fem_polar_rotation(F, R);
    fem_corotated_strain(F, R, eps);
    T ee = T(0);
    CTSURG_UNROLL
    for (int i = 0; i < 9; ++i) ee += eps[i] * eps[i];
    const T tr = eps[0] + eps[4] + eps[8];
    return k.mu * ee + T(0.5) * k.lambda * tr * tr;
  }

  template <class T>
  CTSURG_HD static void first_piola(const FemLawParameters<T>& k, const T* F, T J, T* P) {
    // P = R (2 mu eps + lambda tr(eps) I): the linear stress of the rotated-back strain, rotated.
    T R[9], eps[9];
    fem_polar_rotation(F, R);
    fem_corotated_strain(F, R, eps);
    const T tr = eps[0] + eps[4] + eps[8];
    T sigma[9];
    CTSURG_UNROLL
    for (int i = 0; i < 9; ++i) sigma[i] = T(2) * k.mu * eps[i] + (i % 4 == 0 ? k.lambda * tr : T(0));
    CTSURG_UNROLL
    for (int r = 0; r < 3; ++r)
      CTSURG_UNROLL
      for (int c = 0; c < 3; ++c)
        P[r * 3 + c] = R[r * 3 + 0] * sigma[0 * 3 + c] + R[r * 3 + 1] * sigma[1 * 3 + c] + R[r * 3 + 2] * sigma[2 * 3 + c];
  }

  template <class T>
  CTSURG_HD static void tangent(const FemLawParameters<T>& k, const T* F, T J, T* A) {
    T L[81];
    fem_linear_tangent(k.mu, k.lambda, L);
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
  }
};

}  // namespace ctsurg::sim
