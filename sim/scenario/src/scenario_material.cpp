#include "scenario_material.h"

#include "ctsurg/core/error.h"
#include "point_field.h"

#include <cstdlib>
#include <map>
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

const std::vector<std::string> kValueFields = {"preset", "youngs_modulus_pa", "poisson_ratio", "density_g_per_cm3"};

// The fields of one material: its values and every law's constants (and "law" when with_law).
std::vector<std::string> material_fields(bool with_law) {
  std::vector<std::string> fields = kValueFields;
  if (with_law) fields.push_back("law");
  for (const auto& [field, law] : law_constant_fields()) fields.push_back(field);
  return fields;
}

// f's law (f.law, checked), or default_law when f gives none.
FemLaw law_of(const YamlField& f, ModelKind model, FemLaw default_law) {
  if (!f.has("law")) return default_law;
  if (model != ModelKind::fem) f.child("law").fail("only for kind: fem (the spring models' law is their springs, the vessel's its rod; docs/sim.md)");
  const std::string text = f.child("law").text();
  const auto named = fem_law_named(text);
  if (!named) f.child("law").fail("unknown law '" + text + "' (the laws: " + fem_law_names() + ")");
  return *named;
}

FemMaterial fem_material(FemLaw law, const Material& m, const std::array<double, kFemLawConstants>& constants) {
  FemMaterial material;
  material.law = law;
  material.youngs_modulus = m.youngs_modulus_pa;
  material.poisson_ratio = m.poisson_ratio;
  material.density = m.density;
  material.constants = constants;
  return material;
}

// One material's fields at `f` (the material section, or one of its labels): its law (default_law
// unless f has `law`), preset and values, the law's constants; checked, with f's path in messages.
void parse_material_fields(const YamlField& f, ModelKind model, FemLaw default_law, Material& material, FemLaw& law,
                           std::array<double, kFemLawConstants>& constants) {
  const std::string& name = f.file();
  const auto constant_fields = law_constant_fields();
  law = law_of(f, model, default_law);
  const FemLawInfo& info = fem_law_info(law);
  for (const auto& [field, owner] : constant_fields) {
    if (f.has(field) && (model != ModelKind::fem || owner != law)) {
      f.child(field).fail("a constant of law " + std::string(fem_law_name(owner)) + ", and this material's law is " +
                          (model == ModelKind::fem ? std::string(info.name) : std::string("the ") + to_string(model) + " model's own"));
    }
  }
  constants = {};
  for (int i = 0; i < info.constant_count; ++i) constants[static_cast<size_t>(i)] = f.child(info.constant_names[i]).non_negative();
  const bool stiffness_from_constants = model == ModelKind::fem && fem_youngs_modulus_from_constants(law, constants, 0.25).has_value();
  if (stiffness_from_constants && f.has("youngs_modulus_pa")) {
    f.child("youngs_modulus_pa")
        .fail(std::string(info.name) + "'s stiffness comes from its constants (small-strain E = 2 mu (1 + nu), mu = 2 (c10 + c01)): leave youngs_modulus_pa out");
  }

  material = f.has("preset") ? material_preset(f.child("preset").text(), name, f.child("preset").path())
                             : Material{"custom", 0, 0.45, 1.06e-3, "scenario"};
  if (f.has("youngs_modulus_pa")) material.youngs_modulus_pa = f.child("youngs_modulus_pa").positive();
  if (f.has("poisson_ratio")) material.poisson_ratio = f.child("poisson_ratio").number();
  if (f.has("density_g_per_cm3")) material.density = f.child("density_g_per_cm3").positive() * 1e-3;
  if (!f.has("preset") && !f.has("youngs_modulus_pa") && !stiffness_from_constants) f.fail("give a preset or youngs_modulus_pa");
  if (f.has("youngs_modulus_pa") || f.has("poisson_ratio") || f.has("density_g_per_cm3") || stiffness_from_constants) {
    material.source = f.has("preset") ? material.name + " preset with values from the scenario" : "scenario";
    if (!f.has("preset")) material.name = "custom";
  }
  // validate_material names "material.<field>"; here the field sits at f's path.
  const auto checked = [&](auto&& check) {
    try {
      check();
    } catch (const InputError& e) {
      std::string field = e.field();
      if (field.rfind("material.", 0) == 0) field = field.substr(9);
      throw InputError(name, f.path() + "." + field, e.problem());
    }
  };
  if (stiffness_from_constants) {
    if (!(material.poisson_ratio > -1 && material.poisson_ratio < 0.5)) checked([&] { validate_material(material, name); });  // names nu's range
    material.youngs_modulus_pa = *fem_youngs_modulus_from_constants(law, constants, material.poisson_ratio);
    if (!(material.youngs_modulus_pa > 0)) f.child(info.constant_names[0]).fail("the constants give no stiffness (they sum to 0)");
  }
  checked([&] { validate_material(material, name); });
  if (model == ModelKind::fem) checked([&] { validate_fem_material(fem_material(law, material, constants), "material"); });
}

// material.labels and material.inclusions give each element (tet, tet-mesh spring or grid cell) its
// own material: kind: fem and kind: explicit_springs. The implicit grid's kernel has one stiffness per
// spring direction, and the vessel is one rod.
void refuse_per_element_materials(const YamlField& f, ModelKind model) {
  switch (model) {
    case ModelKind::fem:
    case ModelKind::explicit_springs: return;
    case ModelKind::spring_grid:
      f.fail("not for kind: spring_grid, whose kernel has one stiffness per spring direction; kind: explicit_springs "
             "runs the same grid's springs with a stiffness each, and takes a material per label (docs/sim.md, \"Materials\")");
    case ModelKind::vessel: f.fail("not for kind: vessel (the vessel is one rod of one material)");
  }
}

}  // namespace

void parse_material_section(const YamlField& mat, Scenario& s) {
  std::vector<std::string> known = material_fields(true);
  known.insert(known.end(), {"damping_per_s", "stiffness_damping_s", "labels", "inclusions"});
  mat.only(known);
  // The section's law: its one material's, or the default of its labels and inclusions.
  const FemLaw section_law = law_of(mat, s.model, s.material_law);

  s.label_materials.clear();
  if (mat.has("labels")) {
    // Each tet label its own material; the section's law is the labels' default.
    const YamlField labels = mat.child("labels");
    refuse_per_element_materials(labels, s.model);
    if (!labels.is_map()) labels.fail("a map of tissue labels to materials, e.g. {2: {preset: kidney}, 5: {preset: liver}}");
    for (const std::string& field : material_fields(false))
      if (mat.has(field)) mat.child(field).fail("with material.labels each label gives its own material: move it into the labels");
    const std::vector<std::string> entry_keys = material_fields(true);
    std::map<uint16_t, LabelMaterial> by_label;
    for (const std::string& key : labels.keys()) {
      const YamlField entry = labels.child(key);
      char* end = nullptr;
      const long id = std::strtol(key.c_str(), &end, 10);
      if (key.empty() || *end != '\0' || id < 1 || id > 65535) entry.fail("a tissue label is a whole number from 1 to 65535, got '" + key + "'");
      entry.only(entry_keys);
      LabelMaterial lm;
      lm.label = static_cast<uint16_t>(id);
      lm.field = entry.path();
      parse_material_fields(entry, s.model, section_law, lm.material, lm.law, lm.constants);
      if (!by_label.emplace(lm.label, lm).second) entry.fail("label " + std::to_string(id) + " is given twice");
    }
    if (by_label.empty()) labels.fail("names no label");
    if (by_label.size() > static_cast<size_t>(kFemMaxMaterials)) {
      labels.fail("at most " + std::to_string(kFemMaxMaterials) + " labels with materials, got " + std::to_string(by_label.size()));
    }
    for (auto& [label, lm] : by_label) s.label_materials.push_back(lm);
    // The first label's material stands for the model where one material is reported.
    s.material = s.label_materials.front().material;
    s.material_law = s.label_materials.front().law;
    s.law_constants = s.label_materials.front().constants;
  } else {
    parse_material_fields(mat, s.model, s.material_law, s.material, s.material_law, s.law_constants);
  }
  s.inclusions.clear();
  if (mat.has("inclusions")) {
    const YamlField list = mat.child("inclusions");
    refuse_per_element_materials(list, s.model);
    if (!list.is_sequence()) list.fail("a list of spheres of other materials, e.g. [{sphere: {at_fraction: [0.5, 0.5, 0.5], radius_mm: 8}, preset: tumour}]");
    std::vector<std::string> keys = material_fields(true);
    keys.push_back("sphere");
    for (const YamlField& item : list.items()) {
      item.only(keys);
      InclusionMaterial inc;
      inc.field = item.path();
      const YamlField sphere = item.child("sphere");
      sphere.only({"position_mm", "at_fraction", "radius_mm"});
      inc.centre = point_of(sphere, false);
      inc.radius_mm = sphere.child("radius_mm").positive();
      parse_material_fields(item, s.model, section_law, inc.material, inc.law, inc.constants);
      s.inclusions.push_back(inc);
    }
    if (s.label_materials.size() + s.inclusions.size() + (s.label_materials.empty() ? 1 : 0) > static_cast<size_t>(kFemMaxMaterials)) {
      list.fail("at most " + std::to_string(kFemMaxMaterials) + " materials in a model (labels, inclusions and the tissue's)");
    }
  }
  if (mat.has("damping_per_s")) s.damping_per_s = mat.child("damping_per_s").non_negative();
  if (mat.has("stiffness_damping_s")) {
    if (s.model != ModelKind::fem || s.fem_solver != FemSolver::implicit)
      mat.child("stiffness_damping_s").fail("only for kind: fem with solver: implicit (Rayleigh stiffness damping)");
    s.stiffness_damping_s = mat.child("stiffness_damping_s").non_negative();
  }
}

FemMaterial fem_material_of(const Scenario& s) { return fem_material(s.material_law, s.material, s.law_constants); }

FemMaterial fem_material_of(const ElementMaterial& m) { return fem_material(m.law, m.material, m.constants); }

}  // namespace ctsurg::sim
