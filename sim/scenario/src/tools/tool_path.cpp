#include "tool_path.h"

#include "point_field.h"

#include <limits>
#include <optional>

namespace ctsurg::sim {
namespace {

// A keyframe's orientation: quaternion: [w, x, y, z] or rotation: {axis: [x, y, z], angle_deg: a}.
std::optional<Quaternion> keyframe_rotation(const YamlField& key) {
  if (key.has("quaternion") && key.has("rotation")) key.fail("give one of quaternion, rotation");
  if (key.has("quaternion")) {
    const YamlField q = key.child("quaternion");
    const auto items = q.items();
    if (items.size() != 4) q.fail("expected [w, x, y, z]");
    Quaternion v{};
    for (size_t i = 0; i < 4; ++i) v[i] = items[i].number();
    return checked_rotation(v, q.file(), q.path());
  }
  if (key.has("rotation")) {
    const YamlField r = key.child("rotation");
    r.only({"axis", "angle_deg"});
    return axis_angle_rotation(r.child("axis").vec3(), r.child("angle_deg").number(), r.file(), r.path());
  }
  return std::nullopt;
}

}  // namespace

std::vector<std::string> path_tool_fields(std::initializer_list<const char*> own) {
  std::vector<std::string> fields{"start_s", "end_s", "path"};
  fields.insert(fields.end(), own.begin(), own.end());
  fields.emplace_back("snap_to_tissue");
  return fields;
}

void read_tool_path(const YamlField& f, ToolAction& t, bool rotations, const std::string& rotation_refusal) {
  const auto keys = f.child("path").items();
  if (keys.empty()) f.child("path").fail("needs at least one keyframe");
  for (size_t i = 0; i < keys.size(); ++i) {
    if (rotations) {
      keys[i].only({"t", "position_mm", "at_fraction", "offset_mm", "quaternion", "rotation"});
    } else {
      keys[i].only({"t", "position_mm", "at_fraction", "offset_mm"});
    }
    Keyframe k;
    k.t = keys[i].child("t").non_negative();
    if (i > 0 && !(k.t > t.path.back().t)) keys[i].child("t").fail("keyframe times must increase");
    k.point = point_of(keys[i], i > 0);
    k.rotation = keyframe_rotation(keys[i]);
    if (!rotation_refusal.empty() && k.rotation && rotation_angle_deg(*k.rotation) > 1e-9) {
      keys[i].child(keys[i].has("rotation") ? "rotation" : "quaternion").fail(rotation_refusal);
    }
    t.path.push_back(k);
  }
  t.start_s = f.has("start_s") ? f.child("start_s").non_negative() : t.path.front().t;
  t.end_s = f.has("end_s") ? f.child("end_s").positive() : std::numeric_limits<double>::infinity();
  if (!(t.end_s > t.start_s)) f.child("end_s").fail("must be after start_s");
  if (f.has("snap_to_tissue")) t.snap_to_tissue = f.child("snap_to_tissue").boolean();
}

void read_grip(const YamlField& f, const Scenario& s, ToolAction& t, bool penalty) {
  if (f.has("grip")) {
    const YamlField g = f.child("grip");
    t.grip = g.one_of({"nodes", "volume"}) == "volume" ? HoldGrip::volume : HoldGrip::nodes;
    if (t.grip == HoldGrip::volume && !penalty && s.model != ModelKind::fem) {
      g.fail("volume needs kind: fem (the spring and vessel models load particles)");
    }
    if (t.grip == HoldGrip::volume && penalty && (s.model != ModelKind::fem || s.fem_solver == FemSolver::dynamic)) {
      g.fail("volume needs kind: fem with solver static_equilibrium or implicit (its penalty is stiff for the explicit dynamics; "
             "the spring and vessel models hold particles)");
    }
  }
  const bool volume = t.grip == HoldGrip::volume;
  if (f.has("grip_stiffness_ratio")) {
    if (!volume) f.child("grip_stiffness_ratio").fail("applies to grip: volume only");
    t.grip_stiffness_ratio = f.child("grip_stiffness_ratio").positive();
    if (t.grip_stiffness_ratio > 1e6) f.child("grip_stiffness_ratio").fail("must be <= 1e6 (beyond it the penalty, not the tissue, sets the factor's conditioning)");
  }
  if (f.has("grip_edge_mm")) {
    if (!volume) f.child("grip_edge_mm").fail("applies to grip: volume only");
    t.grip_edge_mm = f.child("grip_edge_mm").positive();
    if (t.grip_edge_mm > t.radius_mm) f.child("grip_edge_mm").fail("must be <= radius_mm");
  }
}

void require_fem_contact_solver(const YamlField& item, const Scenario& s, const char* tool) {
  if (s.model == ModelKind::fem && s.fem_solver != FemSolver::dynamic) {
    item.fail(std::string(tool) +
              " needs solver: dynamic (contact is part of the explicit dynamics only, not of the static or implicit solvers)");
  }
}

}  // namespace ctsurg::sim
