#include "scenario_material.h"

#include "ctsurg/core/error.h"

#include <string>
#include <vector>

namespace ctsurg::sim {
namespace {

// Every law's constant fields, with the law that reads each.
std::vector<std::pair<std::string, FemLaw>> law_constant_fields() {
  std::vector<std::pair<std::string, FemLaw>> fields;
  for (int32_t id = 0; id < kFemLawCount; ++id) {
    const FemLawInfo& info = fem_law_info(static_cast<FemLaw>(id));
    for (int i = 0; i < info.constant_count; ++i) fields.emplace_back(info.constant_names[i], static_cast<FemLaw>(id));
  }
  return fields;
}

}  // namespace

void parse_material_section(const YamlField& mat, Scenario& s) {
  const std::string& name = mat.file();
  std::vector<std::string> known = {"preset", "law", "youngs_modulus_pa", "poisson_ratio", "density_g_per_cm3", "damping_per_s",
                                    "stiffness_damping_s"};
  const auto constant_fields = law_constant_fields();
  for (const auto& [field, law] : constant_fields) known.push_back(field);
  mat.only(known);

  if (mat.has("law")) {
    if (s.model != ModelKind::fem) {
      mat.child("law").fail("only for kind: fem (the spring models' law is their springs, the vessel's its rod; docs/sim.md)");
    }
    const std::string text = mat.child("law").text();
    const auto law = fem_law_named(text);
    if (!law) mat.child("law").fail("unknown law '" + text + "' (the laws: " + fem_law_names() + ")");
    s.material_law = *law;
  }
  const FemLawInfo& info = fem_law_info(s.material_law);
  for (const auto& [field, law] : constant_fields) {
    if (mat.has(field) && (s.model != ModelKind::fem || law != s.material_law)) {
      mat.child(field).fail("a constant of law " + std::string(fem_law_name(law)) + ", and this material's law is " +
                            (s.model == ModelKind::fem ? std::string(info.name) : std::string("the ") + to_string(s.model) + " model's own"));
    }
  }
  s.law_constants = {};
  for (int i = 0; i < info.constant_count; ++i) s.law_constants[static_cast<size_t>(i)] = mat.child(info.constant_names[i]).non_negative();
  const bool stiffness_from_constants = s.model == ModelKind::fem && fem_youngs_modulus_from_constants(s.material_law, s.law_constants, 0.25).has_value();
  if (stiffness_from_constants && mat.has("youngs_modulus_pa")) {
    mat.child("youngs_modulus_pa")
        .fail(std::string(info.name) + "'s stiffness comes from its constants (small-strain E = 2 mu (1 + nu), mu = 2 (c10 + c01)): leave youngs_modulus_pa out");
  }

  s.material = mat.has("preset") ? material_preset(mat.child("preset").text(), name, mat.child("preset").path())
                                 : Material{"custom", 0, 0.45, 1.06e-3, "scenario"};
  if (mat.has("youngs_modulus_pa")) s.material.youngs_modulus_pa = mat.child("youngs_modulus_pa").positive();
  if (mat.has("poisson_ratio")) s.material.poisson_ratio = mat.child("poisson_ratio").number();
  if (mat.has("density_g_per_cm3")) s.material.density = mat.child("density_g_per_cm3").positive() * 1e-3;
  if (!mat.has("preset") && !mat.has("youngs_modulus_pa") && !stiffness_from_constants) mat.fail("give a preset or youngs_modulus_pa");
  if (mat.has("youngs_modulus_pa") || mat.has("poisson_ratio") || mat.has("density_g_per_cm3") || stiffness_from_constants) {
    s.material.source = mat.has("preset") ? s.material.name + " preset with values from the scenario" : "scenario";
    if (!mat.has("preset")) s.material.name = "custom";
  }
  if (stiffness_from_constants) {
    if (!(s.material.poisson_ratio > -1 && s.material.poisson_ratio < 0.5)) validate_material(s.material, name);  // names nu's range
    s.material.youngs_modulus_pa = *fem_youngs_modulus_from_constants(s.material_law, s.law_constants, s.material.poisson_ratio);
    if (!(s.material.youngs_modulus_pa > 0)) mat.child(info.constant_names[0]).fail("the constants give no stiffness (they sum to 0)");
  }
  validate_material(s.material, name);
  if (s.model == ModelKind::fem) {
    try {
      validate_fem_material(fem_material_of(s), "material");
    } catch (const InputError& e) {
      throw InputError(name, "material." + e.field(), e.problem());
    }
  }
  if (mat.has("damping_per_s")) s.damping_per_s = mat.child("damping_per_s").non_negative();
  if (mat.has("stiffness_damping_s")) {
    if (s.model != ModelKind::fem || s.fem_solver != FemSolver::implicit)
      mat.child("stiffness_damping_s").fail("only for kind: fem with solver: implicit (Rayleigh stiffness damping)");
    s.stiffness_damping_s = mat.child("stiffness_damping_s").non_negative();
  }
}

FemMaterial fem_material_of(const Scenario& s) {
  FemMaterial material;
  material.law = s.material_law;
  material.youngs_modulus = s.material.youngs_modulus_pa;
  material.poisson_ratio = s.material.poisson_ratio;
  material.density = s.material.density;
  material.constants = s.law_constants;
  return material;
}

}  // namespace ctsurg::sim
