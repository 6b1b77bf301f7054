// The scenario's `material:` section (docs/sim.md, "Materials"): a preset and/or explicit values
// (Young's modulus, Poisson's ratio, density), damping, and for kind: fem the material law with its own
// constants (material.law; mooney_rivlin's c10_pa and c01_pa). Every value is checked here, with the
// file and the field in the message.
#pragma once

#include "ctsurg/sim/scenario/scenario.h"

#include "yaml_field.h"

namespace ctsurg::sim {

// Parses `material` into s.material, s.material_law, s.law_constants, s.damping_per_s and
// s.stiffness_damping_s. Needs s.model, s.fem_solver (the model section is read first).
void parse_material_section(const YamlField& material, Scenario& s);

// The FEM material of a parsed scenario (its law, E, nu, density and the law's constants), and of one
// of one of its labels or inclusions (material.labels, material.inclusions).
FemMaterial fem_material_of(const Scenario& s);
FemMaterial fem_material_of(const ElementMaterial& m);

}  // namespace ctsurg::sim
