// The CPU build of the FEM kernels (fem_forces_impl.h, fem_explicit_step_impl.h): OpenMP over
// elements, then over nodes, static partitions. Every result is written by exactly one index, so
// the bits do not depend on the thread count. Inverted elements are reduced to the lowest id.
#include "fem_cpu_kernels.h"
#include "fem_tangent_projection.h"

#include "ctsurg/sim/base/parallel.h"

#include <omp.h>

#include <climits>
#include <cmath>

namespace ctsurg::sim::cpu {
namespace {

template <class T>
int32_t forces_impl(const FemElementView<T>& elements, const int32_t* offsets, const int32_t* corners, int32_t nodes,
                    const T* u, T* corner_forces, T* forces, int threads) {
  const int t = thread_count(threads, elements.count);
  int32_t first = INT32_MAX;
#pragma omp parallel num_threads(t)
  {
    if (elements.order == 2) {
#pragma omp for schedule(static) reduction(min : first)
      for (int32_t e = 0; e < elements.count; ++e)
        if (!fem_quadratic_element_force_pass(elements, u, e, corner_forces) && e < first) first = e;
    } else {
#pragma omp for schedule(static) reduction(min : first)
      for (int32_t e = 0; e < elements.count; ++e)
        if (!fem_element_force_pass(elements, u, e, corner_forces) && e < first) first = e;
    }
#pragma omp for schedule(static)
    for (int32_t i = 0; i < nodes; ++i) fem_gather_node_force(offsets, corners, corner_forces, i, forces + 3 * i);
  }
  return first == INT32_MAX ? -1 : first;
}

}  // namespace

int32_t fem_forces(const FemElementView<double>& elements, const int32_t* offsets, const int32_t* corners, int32_t nodes,
                   const double* u, double* corner_forces, double* forces, int threads) {
  return forces_impl(elements, offsets, corners, nodes, u, corner_forces, forces, threads);
}

int32_t fem_forces(const FemElementView<float>& elements, const int32_t* offsets, const int32_t* corners, int32_t nodes,
                   const float* u, float* corner_forces, float* forces, int threads) {
  return forces_impl(elements, offsets, corners, nodes, u, corner_forces, forces, threads);
}

namespace {

// The quadratic element's 30 x 30 tangent by quadrature (fem_quadratic_element_impl.h); false when a
// point's det F <= 0 (K = 0).
bool quadratic_stiffness(const FemElementView<double>& el, const double* u, int32_t e, bool projecting, double* K) {
  double ue[30];
  for (int a = 0; a < 10; ++a)
    for (int c = 0; c < 3; ++c) ue[3 * a + c] = u[3 * el.tets[10 * e + a] + c];
  const double* B = el.dm_inverse + 9 * e;
  for (int i = 0; i < 900; ++i) K[i] = 0;
  for (int q = 0; q < 4; ++q) {
    double l[4], G[30], F[9], A[81];
    fem_quadratic_point(q, l);
    fem_quadratic_gradients(B, l, G);
    fem_quadratic_deformation_gradient(ue, G, F);
    if (!fem_material_tangent(el.material(e), F, A)) {
      for (int i = 0; i < 900; ++i) K[i] = 0;
      return false;
    }
    if (projecting) project_tangent_psd(A);
    fem_add_stiffness_from_tangent(A, G, 10, 0.25 * el.volume[e], K);
  }
  return true;
}

}  // namespace

int32_t fem_stiffness(const FemElementView<double>& el, const double* u, double* k, int threads, bool project) {
  const int t = thread_count(threads, el.count / 8);
  // Only elements whose law's tangent may be indefinite are projected.
  const auto projecting_material = [&](int32_t e) { return project && fem_law_traits(el.material(e).law).indefinite_tangent; };
  int32_t first = INT32_MAX;
  if (el.order == 2) {
#pragma omp parallel for schedule(static) num_threads(t) reduction(min : first)
    for (int32_t e = 0; e < el.count; ++e)
      if (!quadratic_stiffness(el, u, e, projecting_material(e), k + 900 * static_cast<int64_t>(e)) && e < first) first = e;
    return first == INT32_MAX ? -1 : first;
  }
#pragma omp parallel for schedule(static) num_threads(t) reduction(min : first)
  for (int32_t e = 0; e < el.count; ++e) {
    double ue[12], F[9], A[81], g[12];
    for (int a = 0; a < 4; ++a)
      for (int c = 0; c < 3; ++c) ue[3 * a + c] = u[3 * el.tets[4 * e + a] + c];
    const double* B = el.dm_inverse + 9 * e;
    double* K = k + 144 * static_cast<int64_t>(e);
    fem_deformation_gradient(ue, B, F);
    if (!fem_material_tangent(el.material(e), F, A)) {
      for (int i = 0; i < 144; ++i) K[i] = 0;
      if (e < first) first = e;
      continue;
    }
    if (projecting_material(e)) project_tangent_psd(A);
    fem_shape_gradients(B, g);
    fem_stiffness_from_tangent(A, g, el.volume[e], K);
  }
  return first == INT32_MAX ? -1 : first;
}

double fem_strain_energy(const FemElementView<double>& el, const double* u, double* element_energy, int threads) {
  const int t = thread_count(threads, el.count);
#pragma omp parallel for schedule(static) num_threads(t)
  for (int32_t e = 0; e < el.count; ++e) {
    const double* B = el.dm_inverse + 9 * e;
    double w;
    if (el.order == 2) {
      double ue[30];
      for (int a = 0; a < 10; ++a)
        for (int c = 0; c < 3; ++c) ue[3 * a + c] = u[3 * el.tets[10 * e + a] + c];
      w = fem_quadratic_element_energy(el.material(e), ue, B, el.volume[e]);
    } else {
      double ue[12], F[9];
      for (int a = 0; a < 4; ++a)
        for (int c = 0; c < 3; ++c) ue[3 * a + c] = u[3 * el.tets[4 * e + a] + c];
      fem_deformation_gradient(ue, B, F);
      const bool needs_positive_j = fem_law_traits(el.material(e).law).needs_positive_j;
      w = needs_positive_j && !(det3(F) > 0) ? 1e30 : el.volume[e] * fem_energy_density(el.material(e), F);
    }
    element_energy[e] = w >= 1e30 ? HUGE_VAL : w;
  }
  double sum = 0;
  for (int32_t e = 0; e < el.count; ++e) sum += element_energy[e];
  return sum;
}

int32_t fem_explicit_step(const FemElementView<Real>& elements, const FemNodeView& nodes, const FemStepConstants& constants,
                          Real* corner_forces, int threads, int32_t* non_finite_node) {
  const int t = thread_count(threads, elements.count);
  int32_t inverted = INT32_MAX, bad = INT32_MAX;
#pragma omp parallel num_threads(t)
  {
#pragma omp for schedule(static) reduction(min : inverted)
    for (int32_t e = 0; e < elements.count; ++e)
      if (!fem_element_force_pass(elements, nodes.u, e, corner_forces) && e < inverted) inverted = e;
    // The reduction is complete after the loop's barrier: every thread sees the same value.
    if (inverted == INT32_MAX) {
#pragma omp for schedule(static) reduction(min : bad)
      for (int32_t i = 0; i < nodes.count; ++i)
        if (!fem_node_update(nodes, constants, corner_forces, i) && i < bad) bad = i;
    }
  }
  *non_finite_node = bad == INT32_MAX ? -1 : bad;
  return inverted == INT32_MAX ? -1 : inverted;
}

int64_t fem_sphere_contact(Real* u, const double* rest, const Real* inv_mass, int32_t nodes, const FemSphereView& sphere,
                           int threads) {
  const int t = thread_count(threads, nodes);
  int64_t moved = 0;
#pragma omp parallel for schedule(static) num_threads(t) reduction(+ : moved)
  for (int32_t i = 0; i < nodes; ++i) moved += fem_sphere_contact_node(u, rest, inv_mass, sphere, i) ? 1 : 0;
  return moved;
}

int64_t fem_instrument_contact(Real* u, const double* rest, const Real* inv_mass, int32_t nodes, const InstrumentView& instrument,
                               int threads) {
  const int t = thread_count(threads, nodes);
  int64_t moved = 0;
#pragma omp parallel for schedule(static) num_threads(t) reduction(+ : moved)
  for (int32_t i = 0; i < nodes; ++i) moved += push_node_out_of_instrument(instrument, u, rest, inv_mass, i);
  return moved;
}

}  // namespace ctsurg::sim::cpu
