#include "ctsurg/sim/fem/fem_material.h"

#include "ctsurg/sim/fem/kernels/fem_element_impl.h"

#include "ctsurg/core/error.h"

#include <cmath>
#include <string>

namespace ctsurg::sim {

const char* fem_material_model_name(FemMaterialModel model) {
  switch (model) {
    case FemMaterialModel::linear: return "linear";
    case FemMaterialModel::stvk: return "stvk";
    case FemMaterialModel::neo_hookean: return "neo_hookean";
    case FemMaterialModel::corotational: return "corotational";
  }
  return "unknown";
}

void validate_fem_material(const FemMaterial& m, const char* where) {
  const int32_t id = static_cast<int32_t>(m.model);
  if (id < kFemLinear || id > kFemCorotational)
    throw InputError(where, "model", "must be linear, stvk, neo_hookean or corotational, got id " + std::to_string(id));
  if (!(std::isfinite(m.youngs_modulus) && m.youngs_modulus > 0))
    throw InputError(where, "youngs_modulus", "Young's modulus must be finite and > 0 Pa, got " + std::to_string(m.youngs_modulus));
  if (!(std::isfinite(m.poisson_ratio) && m.poisson_ratio > -1 && m.poisson_ratio < 0.5))
    throw InputError(where, "poisson_ratio",
                     "Poisson's ratio must lie in (-1, 0.5) (0.5 = incompressible, not supported by this "
                     "displacement formulation), got " + std::to_string(m.poisson_ratio));
  if (!(std::isfinite(m.density) && m.density > 0))
    throw InputError(where, "density", "density must be finite and > 0 g/mm^3, got " + std::to_string(m.density));
}

LameParameters lame_parameters(const FemMaterial& m) {
  validate_fem_material(m);
  const double e = m.youngs_modulus, nu = m.poisson_ratio;
  return {e / (2 * (1 + nu)), e * nu / ((1 + nu) * (1 - 2 * nu))};
}

bool first_piola_kirchhoff(FemMaterialModel model, const LameParameters& lame, const std::array<double, 9>& F,
                           std::array<double, 9>& P) {
  return fem_first_piola<double>(static_cast<int32_t>(model), lame.mu, lame.lambda, F.data(), P.data());
}

double strain_energy_density(FemMaterialModel model, const LameParameters& lame, const std::array<double, 9>& F) {
  if ((model == FemMaterialModel::neo_hookean || model == FemMaterialModel::corotational) && !(det3(F.data()) > 0)) return HUGE_VAL;
  return fem_energy_density<double>(static_cast<int32_t>(model), lame.mu, lame.lambda, F.data());
}

}  // namespace ctsurg::sim
