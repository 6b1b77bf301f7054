// Per-element kernels of the quadratic (10-node) tetrahedron, total Lagrangian, for the host and the
// CUDA build (STYLE.md rule 5): forces, energy and tangent stiffness by 4-point Gauss quadrature, on
// the material laws of fem_element_impl.h (first Piola-Kirchhoff stress, energy density, dP/dF).
//
// Nodes: the 4 corners of the linear tet, then the 6 edge midpoints in the order (0,1), (1,2), (0,2),
// (0,3), (1,3), (2,3) (VTK_QUADRATIC_TETRA's). The edges are straight (midpoints at the middle), so the
// map from barycentric coordinates is affine: the barycentric gradients grad(l_a) are constant, from
// B = Dm^-1 of the corners (fem_shape_gradients), and the volume V is the corners'. Shape functions
//   corner a     N_a  = l_a (2 l_a - 1)        grad N_a  = (4 l_a - 1) grad l_a
//   edge (i, j)  N_ij = 4 l_i l_j              grad N_ij = 4 (l_i grad l_j + l_j grad l_i)
// F = I + sum_a u_a (x) grad N_a varies linearly inside the element; the integrals are
// sum_q w_q V (.)(l_q) over the 4 points l = (a, b, b, b) and permutations, a = (5 + 3 sqrt 5) / 20,
// b = (5 - sqrt 5) / 20, w_q = 1/4: exact for quadratic integrands (the linear law's stiffness), the
// usual rule for the nonlinear ones (Zienkiewicz, Taylor and Zhu, The Finite Element Method, vol. 1,
// table 6.4). f_a = -sum_q w_q V P(F_q) grad N_a(l_q); K_ab = sum_q w_q V grad N_a^T A(F_q) grad N_b.
//
// Units as fem_element_impl.h: mm, Pa, uN. No std containers, exceptions or virtual calls.
#pragma once

#include "ctsurg/sim/fem/kernels/fem_element_impl.h"

namespace ctsurg::sim {

constexpr int kFemQuadraticNodes = 10;
// The corners of each edge node 4..9.
CTSURG_HD inline void fem_quadratic_edge(int k, int& i, int& j) {
  const int ends[6][2] = {{0, 1}, {1, 2}, {0, 2}, {0, 3}, {1, 3}, {2, 3}};
  i = ends[k][0];
  j = ends[k][1];
}

// Barycentric coordinates of quadrature point q (0..3).
template <class T>
CTSURG_HD inline void fem_quadratic_point(int q, T* l) {
  const T a = T(0.5854101966249685), b = T(0.1381966011250105);
  CTSURG_UNROLL
  for (int k = 0; k < 4; ++k) l[k] = k == q ? a : b;
}

// The 10 shape functions' values at barycentric coordinates l (sum 1).
template <class T>
CTSURG_HD inline void fem_quadratic_shape(const T* l, T* N) {
  CTSURG_UNROLL
  for (int a = 0; a < 4; ++a) N[a] = l[a] * (T(2) * l[a] - T(1));
  CTSURG_UNROLL
  for (int k = 0; k < 6; ++k) {
    int i, j;
    fem_quadratic_edge(k, i, j);
    N[4 + k] = T(4) * l[i] * l[j];
  }
}

// Gradients G[a*3+c] (1/mm) of the 10 shape functions at l, from the corners' B = Dm^-1.
template <class T>
CTSURG_HD inline void fem_quadratic_gradients(const T* B, const T* l, T* G) {
  T g[12];
  fem_shape_gradients(B, g);  // grad l_a
  CTSURG_UNROLL
  for (int a = 0; a < 4; ++a)
    CTSURG_UNROLL
    for (int c = 0; c < 3; ++c) G[a * 3 + c] = (T(4) * l[a] - T(1)) * g[a * 3 + c];
  CTSURG_UNROLL
  for (int k = 0; k < 6; ++k) {
    int i, j;
    fem_quadratic_edge(k, i, j);
    CTSURG_UNROLL
    for (int c = 0; c < 3; ++c) G[(4 + k) * 3 + c] = T(4) * (l[i] * g[j * 3 + c] + l[j] * g[i * 3 + c]);
  }
}

// F = I + sum_a u_a (x) G_a. u: 30 node displacements (node-major, xyz).
template <class T>
CTSURG_HD inline void fem_quadratic_deformation_gradient(const T* u, const T* G, T* F) {
  CTSURG_UNROLL
  for (int r = 0; r < 3; ++r)
    CTSURG_UNROLL
    for (int c = 0; c < 3; ++c) {
      T s = r == c ? T(1) : T(0);
      for (int a = 0; a < kFemQuadraticNodes; ++a) s += u[a * 3 + r] * G[a * 3 + c];
      F[r * 3 + c] = s;
    }
}

// Element forces f (30, uN) from its node displacements u (30 mm). Returns false (forces of the points
// before it summed, the caller reports the element) when some point's det F <= 0.
template <class T>
CTSURG_HD inline bool fem_quadratic_element_forces(const FemLawParameters<T>& k, const T* u, const T* B, T V, T* f) {
  for (int i = 0; i < 3 * kFemQuadraticNodes; ++i) f[i] = T(0);
  bool ok = true;
  for (int q = 0; q < 4; ++q) {
    T l[4], G[30], F[9], P[9];
    fem_quadratic_point(q, l);
    fem_quadratic_gradients(B, l, G);
    fem_quadratic_deformation_gradient(u, G, F);
    ok = fem_first_piola(k, F, P) && ok;
    const T w = T(0.25) * V;
    for (int a = 0; a < kFemQuadraticNodes; ++a)
      CTSURG_UNROLL
      for (int r = 0; r < 3; ++r)
        f[a * 3 + r] -= w * (P[r * 3 + 0] * G[a * 3 + 0] + P[r * 3 + 1] * G[a * 3 + 1] + P[r * 3 + 2] * G[a * 3 + 2]);
  }
  return ok;
}

// Element strain energy (nJ); 1e30 when some point's det F <= 0 for the laws that need det F > 0.
template <class T>
CTSURG_HD inline T fem_quadratic_element_energy(const FemLawParameters<T>& k, const T* u, const T* B, T V) {
  const bool needs_positive_j = fem_law_traits(k.law).needs_positive_j;
  T e = T(0);
  for (int q = 0; q < 4; ++q) {
    T l[4], G[30], F[9];
    fem_quadratic_point(q, l);
    fem_quadratic_gradients(B, l, G);
    fem_quadratic_deformation_gradient(u, G, F);
    if (needs_positive_j && !(det3(F) > T(0))) return T(1e30);
    e += T(0.25) * V * fem_energy_density(k, F);
  }
  return e;
}

// K += w V G^T A G over n nodes: K[(3 a + r) (3 n) + 3 b + j] += w V sum_cd G_ac A[(3 r + c) 9 + 3 j + d] G_bd.
template <class T>
CTSURG_HD inline void fem_add_stiffness_from_tangent(const T* A, const T* G, int n, T wv, T* K) {
  const int m = 3 * n;
  for (int r = 0; r < 3; ++r)
    for (int j = 0; j < 3; ++j)
      for (int b = 0; b < n; ++b) {
        T Ag[3];  // Ag[c] = sum_d A[(r c), (j d)] G_bd
        CTSURG_UNROLL
        for (int c = 0; c < 3; ++c)
          Ag[c] = A[(3 * r + c) * 9 + 3 * j + 0] * G[b * 3 + 0] + A[(3 * r + c) * 9 + 3 * j + 1] * G[b * 3 + 1] +
                  A[(3 * r + c) * 9 + 3 * j + 2] * G[b * 3 + 2];
        for (int a = 0; a < n; ++a)
          K[(3 * a + r) * m + 3 * b + j] += wv * (G[a * 3 + 0] * Ag[0] + G[a * 3 + 1] * Ag[1] + G[a * 3 + 2] * Ag[2]);
      }
}

}  // namespace ctsurg::sim
