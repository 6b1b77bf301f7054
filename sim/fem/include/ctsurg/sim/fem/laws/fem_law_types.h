// What every material law of the tetrahedral FEM shares (one header per law beside this one, chosen by
// fem_law.h's one dispatch): the law's id, its constants in the kernels' scalar, and its description.
//
// A law is a struct with, for the kernels (host and device, templated on the scalar T):
//   energy_density(k, F)            psi(F), Pa = nJ/mm^3 (called with det F > 0 when kNeedsPositiveJ)
//   first_piola(k, F, J, P)         P = dpsi/dF, Pa (J = det F > 0)
//   tangent(k, F, J, A)             A = dP/dF, 9 x 9 row-major over the pairs (r c), (j d): A[(3 r + c) 9 +
//                                   3 j + d] = dP_rc / dF_jd, Pa (J = det F > 0)
// and its traits:
//   kNeedsPositiveJ                 its energy is infinite for det F <= 0 (an inverted element is refused
//                                   by the solvers' line searches rather than given a finite energy)
//   kIndefiniteTangent              its exact tangent may be indefinite (the static and implicit solvers
//                                   project element tangents to PSD when a factorisation fails)
//   kInfo                           name, constants and a line for messages and docs (host only)
// and, optionally, a host check of what the registry's generic checks (finite, >= 0) do not cover:
//   static FemLawProblem problem(const FemLawParameters<double>& k)   {nullptr, nullptr} when valid
// F, P: 3x3 row-major. Units: Pa = g/(mm s^2) (numerically equal in ctsurg's mm-g-s system).
#pragma once

#include <stdint.h>

namespace ctsurg::sim {

// The laws, in the order of their ids (stored in trajectories' provenance by name, not id).
enum class FemLaw : int32_t { linear = 0, stvk = 1, neo_hookean = 2, corotational = 3, mooney_rivlin = 4 };
inline constexpr int kFemLawCount = 5;  // ids 0 .. kFemLawCount - 1

// The constants a law may carry beyond the Lame parameters (mooney_rivlin: c10, c01).
inline constexpr int kFemLawConstants = 2;

// The most materials one model's elements may have (the kernels' element view carries them by value, so
// a kernel launch needs no extra buffer: kernels/fem_forces_impl.h).
inline constexpr int kFemMaxMaterials = 16;

// One material as the kernels see it: its law, the small-strain Lame parameters mu (shear modulus) and
// lambda, Pa, and the law's own constants c[] (kInfo.constant_names says which, in Pa).
template <class T>
struct FemLawParameters {
  FemLaw law = FemLaw::linear;
  T mu = T(0);
  T lambda = T(0);
  T c[kFemLawConstants] = {T(0), T(0)};
};

// A law's description (host): how a scenario names it and its constants, and what they mean.
struct FemLawInfo {
  const char* name;                                // the scenario's material.law, e.g. "neo_hookean"
  const char* summary;                             // one line for messages and docs
  int constant_count;                              // how many of c[] the law reads
  const char* constant_names[kFemLawConstants];    // their scenario fields, e.g. "c10_pa"
  // A law whose constants set its stiffness (constant_count > 0 and these not all 0): its small-strain
  // shear modulus is mu = sum_i shear_weights[i] c[i], and Young's modulus follows from mu and nu
  // (the scenario gives the constants instead of youngs_modulus_pa).
  double shear_weights[kFemLawConstants];
};

// What a law's own check found: the material field to blame and why (both null: nothing).
struct FemLawProblem {
  const char* field;
  const char* problem;
};

}  // namespace ctsurg::sim
