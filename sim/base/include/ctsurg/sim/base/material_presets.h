// Named soft-tissue materials with literature values, and the lookup a scenario's `material: preset`
// uses. Values are small-strain (linear) moduli; soft tissue stiffens with strain, so they are a
// starting point, not a patient's truth (docs/sim.md, "Materials", gives the sources and ranges).
//
// Units: Young's modulus in Pa (= g/(mm s^2) in ctsurg's mm-g-s units), density in g/mm^3.
#pragma once

#include <string>
#include <vector>

namespace ctsurg::sim {

struct Material {
  std::string name;             // preset name, or "custom"
  double youngs_modulus_pa = 0; // E, Pa, > 0
  double poisson_ratio = 0;     // nu, in (-1, 0.5)
  double density = 0;           // g/mm^3, > 0
  std::string source;           // where the values come from (one line)
};

// The presets: myocardium, liver, kidney, vessel_wall, fat, tumour (a stiff inclusion), soft_tissue (a
// generic default).
const std::vector<Material>& material_presets();
// The preset called `name`; InputError(file, field, ...) listing the known names otherwise.
Material material_preset(const std::string& name, const std::string& file = "material",
                         const std::string& field = "material.preset");
// Checks 1 Pa <= E <= 1e11 Pa, -1 < nu < 0.5 and 0.01 <= density <= 25 g/cm^3 (finite);
// InputError(file, "material.<field>", ...) naming the field and the range.
inline constexpr double kMinYoungsModulusPa = 1.0;
inline constexpr double kMaxYoungsModulusPa = 1e11;
void validate_material(const Material& material, const std::string& file = "material");

}  // namespace ctsurg::sim
