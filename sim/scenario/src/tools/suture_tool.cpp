// suture: {start_s, end_s, stitches: [{a, b}], along: {from, to, count, width_mm, across},
// target_length_mm, stiffness_ratio}: stitches placed when its window opens, tightened to
// target_length_mm by its end and kept after (the stitch primitive, springs/suture.h). The window is
// required (the knots tighten over it); no path. The spring models only.
#include "ctsurg/sim/scenario/tool_type.h"
#include "ctsurg/sim/springs/suture.h"
#include "tool_path.h"

#include <cmath>

namespace ctsurg::sim {
namespace {

double stitch_distance(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return std::sqrt(std::pow(b[0] - a[0], 2) + std::pow(b[1] - a[1], 2) + std::pow(b[2] - a[2], 2));
}

void parse_suture(const YamlField& item, const ToolParseContext& context, ToolAction& t) {
  const YamlField f = item.child("suture");
  f.only({"start_s", "end_s", "stitches", "along", "target_length_mm", "stiffness_ratio"});
  t.start_s = f.child("start_s").non_negative();
  t.end_s = f.child("end_s").positive();
  if (!(t.end_s > t.start_s)) f.child("end_s").fail("must be after start_s (the knots tighten from start_s to end_s)");
  if (f.has("target_length_mm")) {
    t.stitch_target_mm = f.child("target_length_mm").non_negative();
    if (t.stitch_target_mm > kMaxStitchLengthMm) f.child("target_length_mm").fail("must be at most " + YamlField::num(kMaxStitchLengthMm) + " mm");
  }
  if (f.has("stiffness_ratio")) {
    t.stitch_stiffness_ratio = f.child("stiffness_ratio").positive();
    if (t.stitch_stiffness_ratio > 1000) f.child("stiffness_ratio").fail("must be at most 1000 (x the stiffest spring)");
  }
  if (f.has("stitches")) {
    const auto items = f.child("stitches").items();
    for (size_t k = 0; k < items.size(); ++k) {
      items[k].only({"a", "b"});
      StitchSpec st{items[k].child("a").vec3(), items[k].child("b").vec3(), items[k].path()};
      const double len = stitch_distance(st.a, st.b);
      if (!(len > 1e-6)) items[k].child("b").fail("is the same point as a (a stitch joins two points)");
      if (len > kMaxStitchLengthMm) {
        items[k].child("b").fail("is " + YamlField::num(len) + " mm from a (at most " + YamlField::num(kMaxStitchLengthMm) + " mm)");
      }
      t.stitches.push_back(st);
    }
  }
  if (f.has("along")) {
    const YamlField a = f.child("along");
    a.only({"from", "to", "count", "width_mm", "across"});
    SutureLine line;
    line.from = a.child("from").vec3();
    line.to = a.child("to").vec3();
    line.count = static_cast<int>(a.child("count").integer(1, 1000));
    line.width_mm = a.child("width_mm").positive();
    line.field = a.path();
    if (line.width_mm > kMaxStitchLengthMm) a.child("width_mm").fail("must be at most " + YamlField::num(kMaxStitchLengthMm) + " mm");
    const double len = stitch_distance(line.from, line.to);
    if (!(len > 1e-6)) a.child("to").fail("is the same point as from (the line needs a direction)");
    if (a.has("across")) {
      const std::array<double, 3> c = a.child("across").vec3();
      const std::array<double, 3> d{(line.to[0] - line.from[0]) / len, (line.to[1] - line.from[1]) / len, (line.to[2] - line.from[2]) / len};
      const double n = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
      const double along = std::abs(c[0] * d[0] + c[1] * d[1] + c[2] * d[2]);
      if (!(n > 0) || along > 0.99 * n) a.child("across").fail("must not be zero or along the line");
      line.across = c;
    }
    t.along = line;
  }
  if (t.stitches.empty() && !t.along) f.fail("give stitches: [{a, b}, ...] and/or along: {from, to, count, width_mm}");
  const Scenario& s = context.scenario;
  if (s.model == ModelKind::vessel) item.fail("suture is not supported by kind: vessel (grab, clamp, force, probe and cut are)");
  if (s.model == ModelKind::fem) {
    item.fail("suture runs on the spring models only (kind: spring_grid or explicit_springs); stitches for kind: fem "
              "are not implemented yet");
  }
}

}  // namespace

extern const ToolType kSutureTool{.name = "suture", .acts = ToolPrimitive::stitch, .record = ToolRecord::stitches,
                                  .record_name = "suture", .live = false, .parse = parse_suture};

}  // namespace ctsurg::sim
