// The scenario's `model:` section: the kind of model, the stage outputs it reads and its own options
// (docs/sim.md, "Scenario files").
#include "scenario_sections.h"

#include "ctsurg/core/error.h"

namespace ctsurg::sim {

void parse_model_section(const YamlField& top, const std::filesystem::path& base_dir, Scenario& s) {
  const YamlField m = top.child("model");
  m.only({"kind", "grid", "surface", "tetmesh", "springs_from", "coupling", "mass_from_fraction", "material_law", "solver", "elements",
          "close_cuts", "centerline"});
  const std::string kind = m.child("kind").one_of({"spring_grid", "explicit_springs", "fem", "vessel"});
  s.model = kind == "spring_grid" ? ModelKind::spring_grid
            : kind == "fem"       ? ModelKind::fem
            : kind == "vessel"    ? ModelKind::vessel
                                  : ModelKind::explicit_springs;
  if (s.model == ModelKind::vessel) {
    // A vessel reads its centerline only and draws its own surface from it (sim/vessel).
    for (const char* other : {"grid", "surface", "tetmesh", "coupling", "mass_from_fraction"}) {
      if (m.has(other)) m.child(other).fail("not for kind: vessel (it reads the centerline only and draws its own surface)");
    }
    const std::string path = m.child("centerline").text();
    if (path.empty()) m.child("centerline").fail("must name a centerline file (ctsurg-centerline)");
    s.centerline = resolve_scenario_path(base_dir, path);
  } else if (m.has("centerline")) {
    m.child("centerline").fail("only for kind: vessel");
  }
  if ((s.model != ModelKind::fem && s.model != ModelKind::vessel) || m.has("grid")) s.grid = resolve_scenario_path(base_dir, m.child("grid").text());
  if (m.has("material_law")) {
    m.child("material_law").fail("the law moved to the material section: write `material: {law: " + m.child("material_law").text() +
                                 ", ...}` (docs/sim.md, \"Materials\")");
  }
  if (m.has("solver") && s.model != ModelKind::fem) m.child("solver").fail("only for kind: fem");
  if (m.has("solver")) {
    const std::string solver = m.child("solver").one_of({"dynamic", "static", "implicit"});
    s.fem_solver = solver == "static" ? FemSolver::static_equilibrium : solver == "implicit" ? FemSolver::implicit : FemSolver::dynamic;
  }
  if (m.has("elements")) {
    if (s.model != ModelKind::fem) m.child("elements").fail("only for kind: fem");
    s.fem_order = m.child("elements").one_of({"linear", "quadratic"}) == std::string("quadratic") ? 2 : 1;
    if (s.fem_order == 2 && s.fem_solver == FemSolver::dynamic)
      m.child("elements").fail("quadratic tets need solver: static or implicit (the explicit dynamics runs linear tets)");
  }
  if (m.has("surface")) s.surface = resolve_scenario_path(base_dir, m.child("surface").text());
  if (m.has("springs_from")) {
    if (s.model != ModelKind::explicit_springs) m.child("springs_from").fail("only for kind: explicit_springs");
    s.springs_from = m.child("springs_from").one_of({"grid", "tetmesh"}) == std::string("grid") ? SpringSource::grid
                                                                                               : SpringSource::tetmesh;
  }
  if (m.has("tetmesh")) s.tetmesh = resolve_scenario_path(base_dir, m.child("tetmesh").text());
  if (s.springs_from == SpringSource::tetmesh && s.tetmesh.empty()) m.child("tetmesh").fail("missing (springs_from: tetmesh)");
  if (s.model == ModelKind::fem && s.tetmesh.empty()) throw InputError(m.file(), "model.tetmesh", "missing (kind: fem needs a tet mesh)");
  if (m.has("coupling")) {
    s.coupling = m.child("coupling").one_of({"trilinear", "nearest_particle"}) == std::string("trilinear")
                     ? CouplingMode::trilinear
                     : CouplingMode::nearest_particle;
  }
  if (m.has("mass_from_fraction")) s.mass_from_fraction = m.child("mass_from_fraction").boolean();
  if (m.has("close_cuts")) {
    if (s.model == ModelKind::fem || s.model == ModelKind::vessel)
      m.child("close_cuts").fail("only for the spring models (a FEM cut's surface is left open; a vessel caps its cuts)");
    s.close_cuts = m.child("close_cuts").boolean();
  }
}

}  // namespace ctsurg::sim
