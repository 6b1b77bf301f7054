// grab: {path, radius_mm, start_s, end_s, snap_to_tissue, local_region_mm, grip, grip_stiffness_ratio,
// grip_edge_mm}: holds what is inside its sphere when its window opens (the nodes, or with grip: volume
// the material: tool_path.h's read_grip) and moves it along the path until the window closes (the hold
// primitive). Only a vessel's grab turns what it holds (keyframe rotations: frames, not points).
#include "ctsurg/sim/scenario/tool_type.h"
#include "tool_path.h"

namespace ctsurg::sim {
namespace {

void parse_grab(const YamlField& item, const ToolParseContext& context, ToolAction& t) {
  const YamlField f = item.child("grab");
  f.only(path_tool_fields({"radius_mm", "local_region_mm", kGripFields[0], kGripFields[1], kGripFields[2]}));
  t.radius_mm = f.child("radius_mm").positive();
  if (f.has("local_region_mm")) t.local_region_mm = f.child("local_region_mm").positive();
  const bool turns = context.scenario.model == ModelKind::vessel;
  read_tool_path(f, t, true, turns ? "" : "a grab turns what it holds only for kind: vessel (the other models grab points, not frames)");
  read_grip(f, context.scenario, t);
}

}  // namespace

extern const ToolType kGrabTool{.name = "grab", .acts = ToolPrimitive::hold, .record = ToolRecord::sphere, .record_name = "grab",
                                .live = true, .parse = parse_grab};

}  // namespace ctsurg::sim
