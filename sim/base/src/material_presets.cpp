#include "ctsurg/sim/base/material_presets.h"

#include "ctsurg/core/error.h"

#include <cmath>

namespace ctsurg::sim {

const std::vector<Material>& material_presets() {
  // Densities: ICRU Report 46 (1992), adult heart, liver and kidney 1.05-1.06 g/cm^3. Moduli: small-
  // strain values from in vivo elastography and ex vivo tests; each tissue's reported range spans a
  // factor of 2-5 (age, pathology, strain level, method), see docs/sim.md.
  static const std::vector<Material> presets = {
      {"myocardium", 30e3, 0.45, 1.06e-3,
       "passive myocardium, small-strain E ~10-50 kPa (ex vivo shear and biaxial tests, Sommer et al. 2015); "
       "density ICRU 46"},
      {"liver", 5.5e3, 0.45, 1.06e-3,
       "healthy liver E ~5.5 kPa (transient elastography, Sandrin et al. 2003); density ICRU 46"},
      {"kidney", 10e3, 0.45, 1.05e-3,
       "renal cortex E ~5-15 kPa (shear-wave elastography of healthy kidneys); density ICRU 46"},
      {"soft_tissue", 10e3, 0.45, 1.06e-3, "generic soft tissue: E 10 kPa, nu 0.45, 1.06 g/cm^3"},
  };
  return presets;
}

Material material_preset(const std::string& name, const std::string& file, const std::string& field) {
  std::string known;
  for (const auto& m : material_presets()) {
    if (m.name == name) return m;
    known += (known.empty() ? "" : ", ") + m.name;
  }
  throw InputError(file, field, "unknown material preset '" + name + "' (known: " + known + ")");
}

void validate_material(const Material& m, const std::string& file) {
  if (!(std::isfinite(m.youngs_modulus_pa) && m.youngs_modulus_pa > 0)) {
    throw InputError(file, "material.youngs_modulus_pa", "must be finite and > 0 Pa, got " + std::to_string(m.youngs_modulus_pa));
  }
  if (!(std::isfinite(m.poisson_ratio) && m.poisson_ratio > -1 && m.poisson_ratio < 0.5)) {
    throw InputError(file, "material.poisson_ratio",
                     "must be in (-1, 0.5) (0.5 is incompressible, which these models cannot represent), got " +
                         std::to_string(m.poisson_ratio));
  }
  if (!(std::isfinite(m.density) && m.density > 0)) {
    throw InputError(file, "material.density_g_per_cm3", "must be finite and > 0");
  }
}

}  // namespace ctsurg::sim
