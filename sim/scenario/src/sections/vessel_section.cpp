// The scenario's `vessel:` section (kind: vessel only): the wall, the rings and the solver of sim/vessel.
#include "scenario_sections.h"

#include "ctsurg/core/error.h"

namespace ctsurg::sim {

void parse_vessel_section(const YamlField& top, Scenario& s) {
  if (s.model == ModelKind::vessel) {
    const YamlField v = top.child("vessel");
    v.only({"wall_thickness_mm", "spokes", "skinning", "blood_filled", "newton_iterations"});
    s.vessel.wall_thickness_mm = v.child("wall_thickness_mm").positive();
    if (s.vessel.wall_thickness_mm > 50) v.child("wall_thickness_mm").fail("must be at most 50 mm");
    if (v.has("spokes")) s.vessel.spokes = static_cast<int>(v.child("spokes").integer(3, 1024));
    if (v.has("skinning")) {
      s.vessel.skinning = v.child("skinning").one_of({"rmf", "spokes"}) == std::string("rmf") ? VesselSkinning::rmf : VesselSkinning::spokes;
    }
    if (v.has("blood_filled")) s.vessel.blood_filled = v.child("blood_filled").boolean();
    if (v.has("newton_iterations")) s.vessel.newton_iterations = static_cast<int>(v.child("newton_iterations").integer(1, 100));
  } else if (top.has("vessel")) {
    top.child("vessel").fail("only for kind: vessel");
  }
}

}  // namespace ctsurg::sim
