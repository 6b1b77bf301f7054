// probe: {path, radius_mm, start_s, end_s, snap_to_tissue}: pushes the tissue out of its sphere while
// its window is open (the push_sphere primitive). On kind: fem only with solver: dynamic (contact is
// part of the explicit dynamics).
#include "ctsurg/sim/scenario/tool_type.h"
#include "tool_path.h"

namespace ctsurg::sim {
namespace {

void parse_probe(const YamlField& item, const ToolParseContext& context, ToolAction& t) {
  const YamlField f = item.child("probe");
  f.only(path_tool_fields({"radius_mm"}));
  t.radius_mm = f.child("radius_mm").positive();
  read_tool_path(f, t, false);
  require_fem_contact_solver(item, context.scenario, "probe");
}

}  // namespace

extern const ToolType kProbeTool{.name = "probe", .acts = ToolPrimitive::push_sphere, .record = ToolRecord::sphere,
                                 .record_name = "probe", .live = true, .parse = parse_probe};

}  // namespace ctsurg::sim
