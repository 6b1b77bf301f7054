// Compressible Mooney-Rivlin with two constants c10, c01 (Pa), in the form that is stress free at rest
// and reduces to Neo-Hookean for c01 = 0 (Bonet and Wood 2008, section 6.5, with the volumetric term of
// eq. 6.28):
//   psi = c10 (I1 - 3) + c01 (I2 - 3) - m ln J + lambda'/2 (ln J)^2,   m = 2 (c10 + 2 c01),
//   I1 = tr C,  I2 = (I1^2 - tr C^2)/2,  C = F^T F,
//   P = 2 c10 F + 2 c01 (I1 F - F C) + (lambda' ln J - m) F^-T,
//   A = 2 c10 d_rj d_cd + 2 c01 (2 F_rc F_jd + I1 d_rj d_cd - d_rj C_dc - F_rd F_jc - (F F^T)_rj d_cd)
//       + (m - lambda' ln J) G_rd G_jc + lambda' G_rc G_jd,   G = F^-T.
// Linearised at rest it is linear elasticity with shear modulus mu = 2 (c10 + c01) and first Lame
// parameter lambda' + 4 c01, so lambda' = lambda - 4 c01 with lambda the small-strain Lame parameter of
// mu and Poisson's ratio: the law, the linear law and the critical time step agree for small strains.
// The material needs lambda' > 0 (else the energy falls without bound under compression: problem()).
// Anchor: SOFA's hyperelastic material/MooneyRivlin.h (an isochoric form of the same invariants).
#pragma once

#include "ctsurg/sim/fem/kernels/fem_matrix3_impl.h"
#include "ctsurg/sim/fem/laws/fem_law_types.h"

namespace ctsurg::sim {

struct MooneyRivlinLaw {
  static constexpr bool kNeedsPositiveJ = true;
  static constexpr bool kIndefiniteTangent = true;
  static constexpr FemLawInfo kInfo{"mooney_rivlin", "compressible Mooney-Rivlin, two constants (Bonet and Wood 2008)", 2,
                                    {"c10_pa", "c01_pa"}, {2, 2}};

  // lambda' = lambda - 4 c01 > 0, checked when a material is validated (fem_material.h).
  static FemLawProblem problem(const FemLawParameters<double>& k) {
    if (k.lambda - 4 * k.c[1] > 0) return {nullptr, nullptr};
    return {"poisson_ratio", "mooney_rivlin needs lambda - 4 c01 > 0 (its volumetric term): raise poisson_ratio or lower c01_pa"};
  }

  // c10, c01, lambda' and m of k (see above).
  template <class T>
  struct Constants {
    T c10, c01, lambda, m;
    CTSURG_HD explicit Constants(const FemLawParameters<T>& k)
        : c10(k.c[0]), c01(k.c[1]), lambda(k.lambda - T(4) * k.c[1]), m(T(2) * (k.c[0] + T(2) * k.c[1])) {}
  };

  // C = F^T F, F F^T and I1 = tr C.
  template <class T>
  CTSURG_HD static T invariants(const T* F, T* C, T* FFt) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) {
        C[r * 3 + c] = F[0 * 3 + r] * F[0 * 3 + c] + F[1 * 3 + r] * F[1 * 3 + c] + F[2 * 3 + r] * F[2 * 3 + c];
        FFt[r * 3 + c] = F[r * 3 + 0] * F[c * 3 + 0] + F[r * 3 + 1] * F[c * 3 + 1] + F[r * 3 + 2] * F[c * 3 + 2];
      }
    return C[0] + C[4] + C[8];
  }

  template <class T>
  CTSURG_HD static T energy_density(const FemLawParameters<T>& k, const T* F) {
    const Constants<T> q(k);
    T C[9], FFt[9];
    const T i1 = invariants(F, C, FFt);
    T cc = T(0);
    for (int i = 0; i < 9; ++i) cc += C[i] * C[i];
    const T i2 = T(0.5) * (i1 * i1 - cc);
    const T lj = kernel_log(det3(F));
    return q.c10 * (i1 - T(3)) + q.c01 * (i2 - T(3)) - q.m * lj + T(0.5) * q.lambda * lj * lj;
  }

  template <class T>
  CTSURG_HD static void first_piola(const FemLawParameters<T>& k, const T* F, T J, T* P) {
    const Constants<T> q(k);
    T C[9], FFt[9], G[9];
    const T i1 = invariants(F, C, FFt);
    cofactor3(F, G);  // F^-T = G / J
    const T a = (q.lambda * kernel_log(J) - q.m) / J;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) {
        const T fc = F[r * 3 + 0] * C[0 * 3 + c] + F[r * 3 + 1] * C[1 * 3 + c] + F[r * 3 + 2] * C[2 * 3 + c];
        P[r * 3 + c] = T(2) * q.c10 * F[r * 3 + c] + T(2) * q.c01 * (i1 * F[r * 3 + c] - fc) + a * G[r * 3 + c];
      }
  }

  template <class T>
  CTSURG_HD static void tangent(const FemLawParameters<T>& k, const T* F, T J, T* A) {
    const Constants<T> q(k);
    T C[9], FFt[9], G[9];
    const T i1 = invariants(F, C, FFt);
    cofactor3(F, G);
    for (int i = 0; i < 9; ++i) G[i] /= J;
    const T a = q.m - q.lambda * kernel_log(J);
    const T c01x2 = T(2) * q.c01;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        for (int j = 0; j < 3; ++j)
          for (int d = 0; d < 3; ++d) {
            const T drj = r == j ? T(1) : T(0), dcd = c == d ? T(1) : T(0);
            const T i2_part = T(2) * F[r * 3 + c] * F[j * 3 + d] + i1 * drj * dcd - drj * C[d * 3 + c] - F[r * 3 + d] * F[j * 3 + c] -
                              FFt[r * 3 + j] * dcd;
            A[(3 * r + c) * 9 + 3 * j + d] = T(2) * q.c10 * drj * dcd + c01x2 * i2_part + a * G[r * 3 + d] * G[j * 3 + c] +
                                             q.lambda * G[r * 3 + c] * G[j * 3 + d];
          }
  }
};

}  // namespace ctsurg::sim
