// Per-element kernels of the linear (4-node) tetrahedron, total Lagrangian, written once for the host
// and the CUDA build (STYLE.md rule 5): deformation gradient, the first Piola-Kirchhoff stress, strain
// energy and material tangent dP/dF of an element's law (laws/fem_law.h: one header per law), nodal
// forces and the 12x12 tangent stiffness.
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

#include "ctsurg/sim/fem/kernels/fem_matrix3_impl.h"
#include "ctsurg/sim/fem/laws/fem_law.h"

#include <math.h>
#include <stdint.h>

namespace ctsurg::sim {

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

// P(F) of the law k.law; returns false and P = 0 when det F <= 0 (inverted: the caller reports it).
template <class T>
CTSURG_HD inline bool fem_first_piola(const FemLawParameters<T>& k, const T* F, T* P) {
  const T J = det3(F);
  if (!(J > T(0))) {
    CTSURG_UNROLL
    for (int i = 0; i < 9; ++i) P[i] = T(0);
    return false;
  }
  fem_visit_law(k.law, FemLawFirstPiola<T>{k, F, J, P});
  return true;
}

// Strain energy density psi(F), Pa; 1e30 for a law that needs det F > 0 when det F <= 0.
template <class T>
CTSURG_HD inline T fem_energy_density(const FemLawParameters<T>& k, const T* F) {
  return fem_visit_law(k.law, FemLawEnergyDensity<T>{k, F});
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
CTSURG_HD inline bool fem_element_forces(const FemLawParameters<T>& k, const T* u, const T* B, T V, T* f) {
  T F[9], P[9];
  fem_deformation_gradient(u, B, F);
  const bool ok = fem_first_piola(k, F, P);
  fem_corner_forces(P, B, V, f);
  return ok;
}

// The material tangent A = dP/dF of the law k.law at F (9 x 9, row-major over the pairs (r c) and (j d):
// A[(3 r + c) 9 + 3 j + d] = dP_rc / dF_jd; each law's header gives its formula). Returns false for
// det F <= 0 (A = 0).
template <class T>
CTSURG_HD inline bool fem_material_tangent(const FemLawParameters<T>& k, const T* F, T* A) {
  const T J = det3(F);
  if (!(J > T(0))) {
    for (int i = 0; i < 81; ++i) A[i] = T(0);
    return false;
  }
  fem_visit_law(k.law, FemLawTangent<T>{k, F, J, A});
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
CTSURG_HD inline bool fem_element_stiffness(const FemLawParameters<T>& k, const T* u, const T* B, T V, T* K) {
  T F[9], g[12], A[81];
  fem_deformation_gradient(u, B, F);
  if (!fem_material_tangent(k, F, A)) {
    for (int i = 0; i < 144; ++i) K[i] = T(0);
    return false;
  }
  fem_shape_gradients(B, g);
  fem_stiffness_from_tangent(A, g, V, K);
  return true;
}

}  // namespace ctsurg::sim
