// Per-index kernels of the FEM force passes (host and device): an element pass writes each element's
// 12 corner forces to its own slots, a node pass gathers them through the node -> (element, corner)
// CSR (STYLE.md rule 6: no atomics; the sum runs over the row in element order, so the bits do not
// depend on the thread count). Displacements are #N x 3 row-major.
#pragma once

#include "ctsurg/sim/fem/kernels/fem_element_impl.h"
#include "ctsurg/sim/fem/kernels/fem_quadratic_element_impl.h"

namespace ctsurg::sim {

template <class T>
struct FemElementView {
  const int32_t* tets = nullptr;  // #T x 4
  const T* dm_inverse = nullptr;  // #T x 9
  const T* volume = nullptr;      // #T mm^3
  int32_t count = 0;              // #T
  int32_t order = 1;              // 1: tets #T x 4; 2: #T x 10 (quadratic; host only)
  // Element e's law and constants: materials[element_material[e]], or materials[0] for every element
  // when element_material is null (one material).
  const int32_t* element_material = nullptr;  // #T, each < the model's material count
  FemLawParameters<T> materials[kFemMaxMaterials];

  CTSURG_HD const FemLawParameters<T>& material(int32_t e) const { return materials[element_material ? element_material[e] : 0]; }
};

// Element e's nodal displacements (N nodes: 4 for linear tets, 10 for quadratic) into ue[0 .. 3 N - 1].
template <int N, class T>
CTSURG_HD inline void fem_gather_element(const int32_t* tets, const T* u, int32_t e, T* ue) {
  CTSURG_UNROLL
  for (int a = 0; a < N; ++a) {
    const int32_t n = tets[N * e + a];
    ue[3 * a] = u[3 * n];
    ue[3 * a + 1] = u[3 * n + 1];
    ue[3 * a + 2] = u[3 * n + 2];
  }
}

// Element e: its corner forces into corner_forces[12 e .. 12 e + 11]; false when inverted.
template <class T>
CTSURG_HD inline bool fem_element_force_pass(const FemElementView<T>& v, const T* u, int32_t e, T* corner_forces) {
  T ue[12];
  fem_gather_element<4>(v.tets, u, e, ue);
  return fem_element_forces(v.material(e), ue, v.dm_inverse + 9 * e, v.volume[e], corner_forces + 12 * e);
}

// Quadratic element e: its 10 nodes' forces into slot_forces[30 e .. 30 e + 29]; false when inverted.
template <class T>
CTSURG_HD inline bool fem_quadratic_element_force_pass(const FemElementView<T>& v, const T* u, int32_t e, T* slot_forces) {
  T ue[30];
  fem_gather_element<10>(v.tets, u, e, ue);
  return fem_quadratic_element_forces(v.material(e), ue, v.dm_inverse + 9 * e, v.volume[e], slot_forces + 30 * e);
}

// Node i: the sum of its corners' forces, in CSR order.
template <class T>
CTSURG_HD inline void fem_gather_node_force(const int32_t* offsets, const int32_t* corners, const T* corner_forces,
                                            int32_t i, T* f) {
  T fx = T(0), fy = T(0), fz = T(0);
  for (int32_t k = offsets[i]; k < offsets[i + 1]; ++k) {
    const T* c = corner_forces + 3 * corners[k];  // npe e + a -> 3 npe e + 3 a
    fx += c[0];
    fy += c[1];
    fz += c[2];
  }
  f[0] = fx;
  f[1] = fy;
  f[2] = fz;
}

}  // namespace ctsurg::sim
