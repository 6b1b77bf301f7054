#include "ctsurg/sim/base/material_presets.h"

#include "ctsurg/core/error.h"

#include <cmath>
#include <sstream>

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
      {"vessel_wall", 1.0e6, 0.45, 1.06e-3,
       "abdominal aortic wall, small-strain E of order 1 MPa, stiffening with age and aneurysm (biaxial tests, Vande Geest, "
       "Sacks and Vorp 2006); density ICRU 46"},
      {"fat", 3.25e3, 0.45, 0.95e-3,
       "adipose tissue E 3.25 +- 0.91 kPa (indentation of 169 samples, Samani, Zubovits and Plewes 2007); density ICRU 46 "
       "adipose 0.95 g/cm^3"},
      {"tumour", 40e3, 0.45, 1.06e-3,
       "a stiff tumour inclusion: solid tumours measure E ~20-75 kPa, 4-8 times the parenchyma around them (invasive ductal "
       "carcinoma 19-42 kPa, Samani et al. 2007; hepatocellular carcinoma by elastography); density ICRU 46"},
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
  // Bounds of what is a material at all, not of tissue: 1 Pa (softer than any gel) to 1e11 Pa
  // (steel; cortical bone is about 2e10 Pa), 0.01 to 25 g/cm^3. Beyond them the critical time step
  // underflows or overflows, and the run would fail later with a message about the step instead.
  if (!(std::isfinite(m.youngs_modulus_pa) && m.youngs_modulus_pa >= kMinYoungsModulusPa &&
        m.youngs_modulus_pa <= kMaxYoungsModulusPa)) {
    throw InputError(file, "material.youngs_modulus_pa",
                     "must be from 1 Pa to 1e11 Pa (soft tissue is 1e2 .. 1e6 Pa), got " + message_number(m.youngs_modulus_pa));
  }
  if (!(std::isfinite(m.poisson_ratio) && m.poisson_ratio > -1 && m.poisson_ratio < 0.5)) {
    throw InputError(file, "material.poisson_ratio",
                     "must be in (-1, 0.5) (0.5 is incompressible, which these models cannot represent), got " +
                         std::to_string(m.poisson_ratio));
  }
  if (!(std::isfinite(m.density) && m.density >= 1e-5 && m.density <= 2.5e-2)) {
    throw InputError(file, "material.density_g_per_cm3",
                     "must be from 0.01 to 25 g/cm^3 (tissue is about 1.05), got " + message_number(m.density * 1e3));
  }
}

}  // namespace ctsurg::sim
