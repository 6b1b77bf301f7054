// force: {path, radius_mm, force_n, start_s, end_s, snap_to_tissue, local_region_mm, grip, grip_edge_mm}:
// a total force (N, LPS) shared by the tissue inside its sphere when its window opens, until it closes
// (the load primitive: the FEM paper's point load): equally by the nodes there, or with grip: volume
// (kind: fem) over the material there by volume (fem/fem_tools.h), which converges as the mesh is refined.
#include "ctsurg/sim/scenario/tool_type.h"
#include "tool_path.h"

namespace ctsurg::sim {
namespace {

void parse_force(const YamlField& item, const ToolParseContext& context, ToolAction& t) {
  const YamlField f = item.child("force");
  f.only(path_tool_fields({"radius_mm", "force_n", "local_region_mm", kGripFields[0], kGripFields[2]}));
  t.radius_mm = f.child("radius_mm").positive();
  t.force_n = f.child("force_n").vec3();
  if (f.has("local_region_mm")) t.local_region_mm = f.child("local_region_mm").positive();
  read_tool_path(f, t, false);
  read_grip(f, context.scenario, t, false);
}

}  // namespace

extern const ToolType kForceTool{.name = "force", .acts = ToolPrimitive::load, .record = ToolRecord::sphere, .record_name = "force",
                                 .live = false, .parse = parse_force};

}  // namespace ctsurg::sim
