#include "ctsurg/sim/scenario/scenario_model.h"

namespace ctsurg::sim {

ModelInputs model_inputs(const Scenario& s) {
  ModelInputs in;
  in.grid = s.model != ModelKind::fem && s.model != ModelKind::vessel;
  in.centerline = s.model == ModelKind::vessel;
  in.tetmesh = s.model == ModelKind::fem || (s.model == ModelKind::explicit_springs && s.springs_from == SpringSource::tetmesh);
  in.surface = !s.surface.empty() && s.model != ModelKind::vessel;
  return in;
}

std::string model_label(const Scenario& s) {
  switch (s.model) {
    case ModelKind::spring_grid: return "spring_grid";
    case ModelKind::explicit_springs:
      return s.springs_from == SpringSource::grid ? "explicit_springs (grid)" : "explicit_springs (tetmesh)";
    case ModelKind::vessel: return s.vessel.skinning == VesselSkinning::rmf ? "vessel (rmf)" : "vessel (spokes)";
    case ModelKind::fem: {
      // One law (per label too when they share it), or the laws of the labels: "fem neo_hookean+linear".
      std::string laws = fem_law_name(s.material_law);
      const auto add = [&](FemLaw law) {
        if (laws.find(fem_law_name(law)) == std::string::npos) laws += std::string("+") + fem_law_name(law);
      };
      for (const LabelMaterial& m : s.label_materials) add(m.law);
      for (const InclusionMaterial& m : s.inclusions) add(m.law);
      return "fem " + laws + (s.fem_order == 2 ? " quadratic" : "") +
             (s.fem_solver == FemSolver::dynamic ? " (dynamic)" : s.fem_solver == FemSolver::implicit ? " (implicit)" : " (static)");
    }
  }
  return "?";
}

}  // namespace ctsurg::sim
