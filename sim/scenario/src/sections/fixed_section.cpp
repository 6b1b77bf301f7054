// The scenario's `fixed:` section: boxes, fractions of the rest bounds, half-spaces and tissue labels
// held still, whole or along some axes (rollers and symmetry planes).
#include "scenario_sections.h"

#include "ctsurg/core/error.h"

namespace ctsurg::sim {
namespace {

FixedRegionSpec fixed_of(const YamlField& item) {
  item.only({"box", "box_fraction", "half_space", "label", "axes"});
  FixedRegionSpec r;
  int given = 0;
  const auto box_of = [&](const YamlField& b) {
    b.only({"min", "max"});
    Box box{b.child("min").vec3(), b.child("max").vec3()};
    for (int c = 0; c < 3; ++c) {
      if (box.min[static_cast<size_t>(c)] > box.max[static_cast<size_t>(c)]) b.child("max").fail("each max must be >= its min");
    }
    return box;
  };
  if (item.has("box")) {
    r.kind = FixedRegionSpec::Kind::box;
    r.box = box_of(item.child("box"));
    ++given;
  }
  if (item.has("box_fraction")) {
    r.kind = FixedRegionSpec::Kind::box_fraction;
    r.box = box_of(item.child("box_fraction"));
    ++given;
  }
  if (item.has("half_space")) {
    const YamlField h = item.child("half_space");
    h.only({"point_mm", "normal"});
    r.kind = FixedRegionSpec::Kind::half_space;
    r.half_space = {h.child("point_mm").vec3(), h.child("normal").vec3()};
    if (r.half_space.normal == std::array<double, 3>{0, 0, 0}) h.child("normal").fail("must not be zero");
    ++given;
  }
  if (item.has("label")) {
    r.kind = FixedRegionSpec::Kind::label;
    r.label = static_cast<uint16_t>(item.child("label").integer(1, 65535));
    ++given;
  }
  if (given != 1) item.fail("each fixed region is exactly one of box, box_fraction, half_space, label");
  if (item.has("axes")) {
    // Rollers and symmetry planes: only these components are held.
    r.axes = 0;
    const auto axes = item.child("axes").items();
    if (axes.empty()) item.child("axes").fail("name at least one of x, y, z");
    for (const auto& a : axes) {
      const std::string axis = a.one_of({"x", "y", "z"});
      const uint8_t bit = static_cast<uint8_t>(1u << (axis[0] - 'x'));
      if (r.axes & bit) a.fail("'" + axis + "' is named twice");
      r.axes |= bit;
    }
  }
  return r;
}

}  // namespace

void parse_fixed_section(const YamlField& top, Scenario& s) {
  if (top.has("fixed")) {
    for (const auto& item : top.child("fixed").items()) {
      s.fixed.push_back(fixed_of(item));
      if (s.model == ModelKind::vessel && s.fixed.back().kind == FixedRegionSpec::Kind::label) {
        item.child("label").fail("a centerline has no labels (kind: vessel): use box, box_fraction or half_space");
      }
      if (s.model == ModelKind::vessel && s.fixed.back().axes != 7) item.child("axes").fail("kind: vessel fixes whole atoms");
      if (s.fixed.back().axes != 7 && s.model == ModelKind::fem && s.fem_solver == FemSolver::dynamic) {
        item.child("axes").fail("fixing some axes only needs solver: static or implicit for kind: fem (the explicit "
                                "dynamics fixes whole nodes)");
      }
    }
  }
}

}  // namespace ctsurg::sim
