// The scenario's `contact:` section (kind: fem, solver: dynamic, linear tets): self-contact, the
// contact distance and the bodies separated by label or plane (docs/fem.md, "Contact"). Needs the tools.
#include "scenario_sections.h"

#include "ctsurg/core/error.h"

namespace ctsurg::sim {

void parse_contact_section(const YamlField& top, Scenario& s) {
  if (top.has("contact")) {
    const YamlField c = top.child("contact");
    if (s.model != ModelKind::fem || s.fem_solver != FemSolver::dynamic || s.fem_order != 1) {
      c.fail("only for kind: fem with solver: dynamic and linear elements (contact is part of the explicit dynamics)");
    }
    c.only({"self", "distance_mm", "bodies"});
    s.contact.enabled = true;
    if (c.has("self")) s.contact.self = c.child("self").boolean();
    if (c.has("distance_mm")) s.contact.distance_mm = c.child("distance_mm").positive();
    if (c.has("bodies")) {
      const YamlField b = c.child("bodies");
      b.only({"labels", "planes", "gap_mm"});
      if (b.has("gap_mm")) s.contact.gap_mm = b.child("gap_mm").non_negative();
      if (b.has("labels")) s.contact.split_labels = b.child("labels").boolean();
      if (b.has("planes")) {
        for (const auto& item : b.child("planes").items()) {
          item.only({"point_mm", "normal"});
          HalfSpace h{item.child("point_mm").vec3(), item.child("normal").vec3()};
          if (h.normal == std::array<double, 3>{0, 0, 0}) item.child("normal").fail("must not be zero");
          s.contact.split_planes.push_back(h);
        }
      }
    }
    for (const ToolAction& tool : s.tools) {
      if (tool.acts() == ToolPrimitive::remove) {
        c.fail(std::string("not with a tool that removes tissue (") + tool.label + "): the bodies are the mesh's pieces at the start");
      }
    }
  }
}

}  // namespace ctsurg::sim
