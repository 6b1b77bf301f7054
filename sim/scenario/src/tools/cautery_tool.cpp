// cautery: {path, radius_mm, rate_mm3_per_s, start_s, end_s, snap_to_tissue}: a hot tip that removes the
// tissue inside its sphere while its window is open, at most rate_mm3_per_s of it per second, nearest
// its centre first (the remove primitive); the surface is closed over the
// crater (close_cuts) and the volume removed is the trajectory's removed_volume metric. The spring
// models (particles, springs/particle_removal.h) and the explicit FEM on linear tets (elements,
// fem/fem_element_removal.h); not a vessel (a rod of atoms).
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
  if (s.model == ModelKind::vessel) {
    item.fail("cautery removes tissue from the spring models and the FEM; kind: vessel (a rod of atoms) cannot remove material");
  }
  if (s.model == ModelKind::fem && (s.fem_solver != FemSolver::dynamic || s.fem_order != 1)) {
    item.fail("cautery on kind: fem needs solver: dynamic and elements: linear (the explicit dynamics carries its state over the "
              "elements removed)");
  }
  for (const ToolAction& other : s.tools) {
    if (s.model == ModelKind::fem && other.acts() == ToolPrimitive::separate) {
      item.fail("cautery and a blade (" + other.label + ") on one kind: fem model are not supported");
    }
  }
}

}  // namespace

extern const ToolType kCauteryTool{.name = "cautery", .acts = ToolPrimitive::remove, .record = ToolRecord::sphere,
                                   .record_name = "cautery", .live = false, .parse = parse_cautery};

}  // namespace ctsurg::sim
