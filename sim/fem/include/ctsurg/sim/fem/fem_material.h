// Materials of the tetrahedral FEM (Huang et al., the FEM paper of /work/shared/seeds: eq. 2-5 small
// strain, eq. 6-8 Green-Lagrange strain), as first Piola-Kirchhoff stress P(F) of the deformation
// gradient F (total Lagrangian: stresses per unit rest area).
//
//   linear         eps = (F + F^T)/2 - I,   P = sigma = 2 mu eps + lambda tr(eps) I    (eq. 3-5)
//   stvk           E = (F^T F - I)/2,      S = 2 mu E + lambda tr(E) I,  P = F S       (eq. 6-8)
//   neo_hookean    psi = mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2  (compressible, Bonet & Wood 2008
//                  eq. 6.28),  P = mu (F - F^-T) + lambda ln(J) F^-T
//   corotational   F = R S (polar decomposition), eps = S - I,  P = R (2 mu eps + lambda tr(eps) I),
//                  psi = mu |eps|^2 + lambda/2 tr(eps)^2 (Mueller and Gross 2004, "Interactive virtual
//                  materials", SOFA's default tetrahedral law): the linear law in each element's rotated
//                  frame, so a rigid rotation costs nothing, at the price of linear behaviour in stretch
//
// Lame parameters from Young's modulus E and Poisson's ratio nu: mu = E / (2 (1 + nu)),
// lambda = E nu / ((1 + nu)(1 - 2 nu)).
//
// Units: E, mu, lambda, stresses in Pa = g/(mm s^2) (numerically equal in the mm-g-s system), density
// g/mm^3 (soft tissue 1.06e-3), energy density g/(mm s^2) = nJ/mm^3. Matrices 3x3 row-major.
#pragma once

#include <array>
#include <cstdint>

namespace ctsurg::sim {

enum class FemMaterialModel : int32_t { linear = 0, stvk = 1, neo_hookean = 2, corotational = 3 };

const char* fem_material_model_name(FemMaterialModel model);

struct FemMaterial {
  FemMaterialModel model = FemMaterialModel::neo_hookean;
  double youngs_modulus = 3.0e4;  // E, Pa (> 0); 30 kPa: myocardium-like soft tissue
  double poisson_ratio = 0.45;    // nu, -1 < nu < 0.5
  double density = 1.06e-3;       // rho, g/mm^3 (> 0)
};

struct LameParameters {
  double mu = 0;      // shear modulus, Pa
  double lambda = 0;  // first Lame parameter, Pa
};

// Throws InputError(where, "youngs_modulus" | "poisson_ratio" | "density", ...) when E <= 0,
// nu <= -1 or nu >= 0.5 (incompressible: lambda infinite), density <= 0, or any is not finite.
void validate_fem_material(const FemMaterial& material, const char* where = "fem material");
// mu and lambda of a validated material (validates first).
LameParameters lame_parameters(const FemMaterial& material);

// First Piola-Kirchhoff stress P (Pa, 3x3 row-major) at deformation gradient F (3x3 row-major,
// dimensionless). Returns false (and P = 0) when det F <= 0 (an inverted element), never NaN.
bool first_piola_kirchhoff(FemMaterialModel model, const LameParameters& lame, const std::array<double, 9>& F,
                           std::array<double, 9>& P);
// Strain energy density psi(F), Pa = nJ/mm^3; +infinity for neo_hookean and corotational when det F <= 0.
double strain_energy_density(FemMaterialModel model, const LameParameters& lame, const std::array<double, 9>& F);

}  // namespace ctsurg::sim
