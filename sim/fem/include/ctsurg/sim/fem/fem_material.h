// A material of the tetrahedral FEM on the host: its law (laws/fem_law.h: one header per law, with its
// energy density, first Piola-Kirchhoff stress P(F), tangent dP/dF and traits), its small-strain
// stiffness, density and the law's own constants; checked once, then handed to the kernels as
// FemLawParameters (total Lagrangian: stresses per unit rest area).
//
// Lame parameters from Young's modulus E and Poisson's ratio nu: mu = E / (2 (1 + nu)),
// lambda = E nu / ((1 + nu)(1 - 2 nu)). A law whose constants set its stiffness (mooney_rivlin: c10,
// c01) has E = 2 mu (1 + nu) with mu = sum_i shear_weights[i] c[i] (FemLawInfo): every law linearises
// at rest to linear elasticity with the material's mu and lambda.
//
// Units: E, mu, lambda, the law's constants and stresses in Pa = g/(mm s^2) (numerically equal in the
// mm-g-s system), density g/mm^3 (soft tissue 1.06e-3), energy density g/(mm s^2) = nJ/mm^3. Matrices
// 3x3 row-major.
#pragma once

#include "ctsurg/sim/fem/laws/fem_law_types.h"

#include <array>
#include <cstdint>
#include <optional>
#include <string>

namespace ctsurg::sim {

// The law's description (name, constants; laws/fem_law_types.h), its scenario name, and the law of a
// scenario name (nullopt for a name no law has).
const FemLawInfo& fem_law_info(FemLaw law);
const char* fem_law_name(FemLaw law);
std::optional<FemLaw> fem_law_named(const std::string& name);
// Every law's name, in id order, comma separated: "linear, stvk, ...".
std::string fem_law_names();

struct FemMaterial {
  FemLaw law = FemLaw::neo_hookean;
  double youngs_modulus = 3.0e4;  // E, Pa (> 0); 30 kPa: myocardium-like soft tissue
  double poisson_ratio = 0.45;    // nu, -1 < nu < 0.5
  double density = 1.06e-3;       // rho, g/mm^3 (> 0)
  // The law's own constants (fem_law_info(law).constant_names, Pa; mooney_rivlin: c10, c01); unused: 0.
  std::array<double, kFemLawConstants> constants{};
};

// A material whose law's constants set its stiffness (mooney_rivlin), with E from them and nu.
FemMaterial fem_material_from_constants(FemLaw law, const std::array<double, kFemLawConstants>& constants,
                                        double poisson_ratio, double density);
// Young's modulus that a law's constants and nu give (E = 2 (1 + nu) sum_i w_i c_i); for a law whose
// constants do not set its stiffness: nullopt.
std::optional<double> fem_youngs_modulus_from_constants(FemLaw law, const std::array<double, kFemLawConstants>& constants,
                                                        double poisson_ratio);

struct LameParameters {
  double mu = 0;      // shear modulus, Pa
  double lambda = 0;  // first Lame parameter, Pa
};

// Throws InputError(where, field, ...) when the law is not one of FemLaw's ("law", naming them),
// E <= 0, nu <= -1 or nu >= 0.5 (incompressible: lambda infinite), density <= 0, any is not finite, a
// constant of the law is negative or not finite (its name), constants a law does not read are not 0,
// or (laws whose constants set the stiffness) they sum to no stiffness, E disagrees with them, or the
// law's volumetric term would be negative (mooney_rivlin: lambda - 4 c01 <= 0: "poisson_ratio").
void validate_fem_material(const FemMaterial& material, const char* where = "fem material");
// mu and lambda of a validated material (validates first).
LameParameters lame_parameters(const FemMaterial& material);
// What the kernels read of a validated material (validates first), in double.
FemLawParameters<double> fem_law_parameters(const FemMaterial& material);

// First Piola-Kirchhoff stress P (Pa, 3x3 row-major) at deformation gradient F (3x3 row-major,
// dimensionless). Returns false (and P = 0) when det F <= 0 (an inverted element), never NaN.
bool first_piola_kirchhoff(const FemLawParameters<double>& law, const std::array<double, 9>& F, std::array<double, 9>& P);
// Strain energy density psi(F), Pa = nJ/mm^3; +infinity when the law needs det F > 0 and det F <= 0.
double strain_energy_density(const FemLawParameters<double>& law, const std::array<double, 9>& F);
// The material tangent A = dP/dF (Pa, 9 x 9 row-major, laws/fem_law_types.h); false (A = 0) for det F <= 0.
bool material_tangent(const FemLawParameters<double>& law, const std::array<double, 9>& F, std::array<double, 81>& A);
// The same for a law without constants of its own (InputError for one with them, whose constants these
// overloads cannot carry).
bool first_piola_kirchhoff(FemLaw law, const LameParameters& lame, const std::array<double, 9>& F, std::array<double, 9>& P);
double strain_energy_density(FemLaw law, const LameParameters& lame, const std::array<double, 9>& F);

}  // namespace ctsurg::sim
