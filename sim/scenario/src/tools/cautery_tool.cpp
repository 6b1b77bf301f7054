// cautery: {path, radius_mm, rate_mm3_per_s, start_s, end_s, snap_to_tissue}: a hot tip that removes the
// tissue inside its sphere while its window is open, at most rate_mm3_per_s of it per second, nearest
// its centre first (the remove primitive: springs/particle_removal.h); the surface is closed over the
// crater (close_cuts) and the volume removed is the trajectory's removed_volume metric. The spring
// models only: a vessel is a rod, and the FEM engine does not remove elements yet.
#include "ctsurg/sim/scenario/tool_type.h"
#include "tool_path.h"

namespace ctsurg::sim {
namespace {

// A generous bound: 1e6 mm^3/s is a litre a second; an electrosurgical tip takes a few mm^3/s.
constexpr double kMaxRemovalRate = 1e6;

void parse_cautery(const YamlField& item, const ToolParseContext& context, ToolAction& t) {
  const YamlField f = item.child("cautery");
  f.only(path_tool_fields({"radius_mm", "rate_mm3_per_s"}));
  t.radius_mm = f.child("radius_mm").positive();
  t.removal_rate_mm3_s = f.child("rate_mm3_per_s").positive();
  if (t.removal_rate_mm3_s > kMaxRemovalRate) {
    f.child("rate_mm3_per_s").fail("must be at most " + YamlField::num(kMaxRemovalRate) + " mm^3/s");
  }
  read_tool_path(f, t, false);
  const Scenario& s = context.scenario;
  if (s.model == ModelKind::vessel || s.model == ModelKind::fem) {
    item.fail("cautery removes tissue from the spring models only (kind: spring_grid or explicit_springs); kind: " +
              std::string(to_string(s.model)) + " cannot remove material");
  }
}

}  // namespace

extern const ToolType kCauteryTool{.name = "cautery", .acts = ToolPrimitive::remove, .record = ToolRecord::sphere,
                                   .record_name = "cautery", .live = false, .parse = parse_cautery};

}  // namespace ctsurg::sim
