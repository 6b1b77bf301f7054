// instrument: {path (with rotations), mesh, grid_spacing_mm, start_s, end_s, snap_to_tissue}: a rigid
// closed mesh (.stl, .obj, .ply; mm, its own frame) that pushes the tissue out of itself (the
// push_shape primitive). Not on a vessel; on kind: fem only with solver: dynamic.
#include "ctsurg/sim/scenario/tool_type.h"
#include "tool_path.h"

namespace ctsurg::sim {
namespace {

void parse_instrument(const YamlField& item, const ToolParseContext& context, ToolAction& t) {
  const YamlField f = item.child("instrument");
  f.only(path_tool_fields({"mesh", "grid_spacing_mm"}));
  const std::string mesh = f.child("mesh").text();
  if (mesh.empty()) f.child("mesh").fail("must name a .stl, .obj or .ply file");
  t.instrument_mesh = resolve_scenario_path(context.base_dir, mesh);
  if (f.has("grid_spacing_mm")) t.instrument_spacing_mm = f.child("grid_spacing_mm").positive();
  read_tool_path(f, t, true);
  const Scenario& s = context.scenario;
  if (s.model == ModelKind::vessel) item.fail("instrument is not supported by kind: vessel (grab, clamp, force, probe and cut are)");
  require_fem_contact_solver(item, s, "instrument");
}

}  // namespace

extern const ToolType kInstrumentTool{.name = "instrument", .acts = ToolPrimitive::push_shape, .record = ToolRecord::instrument,
                                      .record_name = "instrument", .live = false, .parse = parse_instrument};

}  // namespace ctsurg::sim
