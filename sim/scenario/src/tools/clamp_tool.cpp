// clamp: {position_mm | at_fraction, radius_mm, start_s, end_s, snap_to_tissue, local_region_mm, grip,
// grip_stiffness_ratio, grip_edge_mm}: a
// grab that stays where it is put (one keyframe), pinning what it captures for its window (the hold
// primitive; the trajectory records it as a grab).
#include "ctsurg/sim/scenario/tool_type.h"
#include "point_field.h"
#include "tool_path.h"

#include <limits>

namespace ctsurg::sim {
namespace {

void parse_clamp(const YamlField& item, const ToolParseContext& context, ToolAction& t) {
  const YamlField f = item.child("clamp");
  f.only({"start_s", "end_s", "radius_mm", "position_mm", "at_fraction", "snap_to_tissue", "local_region_mm", kGripFields[0], kGripFields[1],
          kGripFields[2]});
  t.radius_mm = f.child("radius_mm").positive();
  if (f.has("local_region_mm")) t.local_region_mm = f.child("local_region_mm").positive();
  t.start_s = f.has("start_s") ? f.child("start_s").non_negative() : 0.0;
  t.end_s = f.has("end_s") ? f.child("end_s").positive() : std::numeric_limits<double>::infinity();
  if (!(t.end_s > t.start_s)) f.child("end_s").fail("must be after start_s");
  Keyframe k;
  k.t = t.start_s;
  k.point = point_of(f, false);
  t.path.push_back(k);
  if (f.has("snap_to_tissue")) t.snap_to_tissue = f.child("snap_to_tissue").boolean();
  read_grip(f, context.scenario, t);
}

}  // namespace

extern const ToolType kClampTool{.name = "clamp", .acts = ToolPrimitive::hold, .record = ToolRecord::sphere, .record_name = "grab",
                                 .live = false, .parse = parse_clamp};

}  // namespace ctsurg::sim
