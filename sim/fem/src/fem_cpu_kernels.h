// The CPU launchers of the FEM kernels (OpenMP), called by the FEM dispatchers after their checks.
#pragma once

#include "ctsurg/sim/fem/kernels/fem_explicit_step_impl.h"
#include "ctsurg/sim/fem/kernels/fem_forces_impl.h"
#include "ctsurg/sim/base/kernels/instrument_contact_impl.h"

#include <cstdint>

namespace ctsurg::sim::cpu {

// Element pass then node gather: forces #N x 3 from displacements u #N x 3. Returns the lowest inverted
// element id or -1. corner_forces: #T x 12 scratch (quadratic elements: #T x 30).
int32_t fem_forces(const FemElementView<double>& elements, const int32_t* offsets, const int32_t* corners,
                   int32_t nodes, const double* u, double* corner_forces, double* forces, int threads);
int32_t fem_forces(const FemElementView<float>& elements, const int32_t* offsets, const int32_t* corners,
                   int32_t nodes, const float* u, float* corner_forces, float* forces, int threads);

// Element strain energies (nJ, #T; +inf for an element whose law needs det F > 0 and has det F <= 0)
// at u; returns their sum in element order (deterministic for any thread count).
double fem_strain_energy(const FemElementView<double>& elements, const double* u, double* element_energy, int threads);

// Element tangent stiffnesses K (#T x 144; quadratic elements #T x 900) at u. project: the material tangents of St. Venant-Kirchhoff
// and Neo-Hookean elements are projected to positive semi-definite first (fem_tangent_projection.h), so
// every K is. Returns the lowest inverted element id or -1.
int32_t fem_stiffness(const FemElementView<double>& elements, const double* u, double* k, int threads, bool project = false);

// One explicit step (fem_explicit_step_impl.h): element pass, node update. Returns the lowest inverted
// element id or -1 (then nothing after the element pass is written) and sets *non_finite_node to the
// lowest node whose new displacement is not finite, or -1.
int32_t fem_explicit_step(const FemElementView<Real>& elements, const FemNodeView& nodes, const FemStepConstants& constants,
                          Real* corner_forces, int threads, int32_t* non_finite_node);

// Sphere contact: nodes (not fixed) inside the sphere moved to its surface along the radius; returns
// how many moved.
int64_t fem_sphere_contact(Real* u, const double* rest, const Real* inv_mass, int32_t nodes, const FemSphereView& sphere,
                           int threads);
// Instrument contact (base/kernels/instrument_contact_impl.h): free nodes inside it projected out; returns
// how many moved.
int64_t fem_instrument_contact(Real* u, const double* rest, const Real* inv_mass, int32_t nodes, const InstrumentView& instrument,
                               int threads);

}  // namespace ctsurg::sim::cpu
