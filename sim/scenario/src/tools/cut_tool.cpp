// cut: {path, blade_edge_mm, start_s, end_s, snap_to_tissue}: a blade whose edge (centred on the path)
// cuts what it crosses as it moves (the separate primitive). On kind: fem only on linear tets.
#include "ctsurg/sim/scenario/tool_type.h"
#include "tool_path.h"

namespace ctsurg::sim {
namespace {

void parse_cut(const YamlField& item, const ToolParseContext& context, ToolAction& t) {
  const YamlField f = item.child("cut");
  f.only(path_tool_fields({"blade_edge_mm"}));
  t.blade_edge_mm = f.child("blade_edge_mm").vec3();
  if (t.blade_edge_mm == std::array<double, 3>{0, 0, 0}) f.child("blade_edge_mm").fail("the blade edge must not be zero");
  read_tool_path(f, t, false);
  if (context.scenario.model == ModelKind::fem && context.scenario.fem_order != 1) {
    item.fail("cut needs linear (4-node) tets; quadratic elements are not cut (elements: linear)");
  }
}

}  // namespace

extern const ToolType kCutTool{.name = "cut", .acts = ToolPrimitive::separate, .record = ToolRecord::blade, .record_name = "cut",
                               .live = true, .parse = parse_cut};

}  // namespace ctsurg::sim
