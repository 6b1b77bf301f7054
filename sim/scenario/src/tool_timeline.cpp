#include "ctsurg/sim/scenario/tool_timeline.h"

#include "rest_bounds.h"

#include "ctsurg/core/error.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace ctsurg::sim {
namespace {

constexpr double kWindowTolerance = 1e-12;  // s: a step landing on start_s in floating point still starts it
constexpr double kOutwardRadiusMm = 15;     // the neighbourhood whose centroid gives a suture line's outward side

Vec3 local(const std::array<double, 3>& lps, const Vec3& origin) { return {lps[0] - origin[0], lps[1] - origin[1], lps[2] - origin[2]}; }

double norm(const Vec3& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

Vec3 cross(const Vec3& a, const Vec3& b) { return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}; }

// A suture's stitches in the local frame: the listed ones, then the line's (scenario.h, SutureLine).
void resolve_stitches(const ToolAction& spec, const std::vector<double>& rest, const Vec3& origin, const std::string& where,
                      std::vector<std::array<Vec3, 2>>& points, std::vector<std::string>& fields) {
  for (const StitchSpec& st : spec.stitches) {
    points.push_back({local(st.a, origin), local(st.b, origin)});
    fields.push_back(st.field);
  }
  if (!spec.along) return;
  const SutureLine& line = *spec.along;
  const Vec3 from = local(line.from, origin), to = local(line.to, origin);
  const Vec3 dir{to[0] - from[0], to[1] - from[1], to[2] - from[2]};
  Vec3 across;
  if (line.across) {
    across = *line.across;
  } else {
    const Vec3 mid{0.5 * (from[0] + to[0]), 0.5 * (from[1] + to[1]), 0.5 * (from[2] + to[2])};
    Vec3 centroid{0, 0, 0};
    double n = 0;
    for (size_t i = 0; i + 2 < rest.size(); i += 3) {
      const Vec3 p{rest[i], rest[i + 1], rest[i + 2]};
      if (norm({p[0] - mid[0], p[1] - mid[1], p[2] - mid[2]}) > kOutwardRadiusMm) continue;
      for (size_t c = 0; c < 3; ++c) centroid[c] += p[c];
      n += 1;
    }
    if (n == 0) throw InputError(where, line.field, "no tissue within 15 mm of the line's middle: put the line on the tissue");
    const Vec3 outward{mid[0] - centroid[0] / n, mid[1] - centroid[1] / n, mid[2] - centroid[2] / n};
    across = cross(dir, outward);
    if (!(norm(across) > 1e-6 * norm(dir) * std::max(1.0, norm(outward)))) {
      throw InputError(where, line.field + ".across", "the tissue's outward direction is along the line here: give across: [x, y, z]");
    }
  }
  // Only the part of `across` perpendicular to the line, unit length.
  const double dd = dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2];
  const double along = (across[0] * dir[0] + across[1] * dir[1] + across[2] * dir[2]) / dd;
  Vec3 u{across[0] - along * dir[0], across[1] - along * dir[1], across[2] - along * dir[2]};
  const double un = norm(u);
  for (double& c : u) c *= 0.5 * line.width_mm / un;
  for (int k = 0; k < line.count; ++k) {
    const double f = (k + 0.5) / line.count;
    const Vec3 p{from[0] + f * dir[0], from[1] + f * dir[1], from[2] + f * dir[2]};
    points.push_back({Vec3{p[0] - u[0], p[1] - u[1], p[2] - u[2]}, Vec3{p[0] + u[0], p[1] + u[1], p[2] + u[2]}});
    fields.push_back(line.field + " (stitch " + std::to_string(k + 1) + " of " + std::to_string(line.count) + ")");
  }
}

}  // namespace

Vec3 ToolTimeline::Path::at(double time) const {
  if (time <= t.front()) return p.front();
  if (time >= t.back()) return p.back();
  const size_t k = static_cast<size_t>(std::upper_bound(t.begin(), t.end(), time) - t.begin());
  const double a = (time - t[k - 1]) / (t[k] - t[k - 1]);
  return {p[k - 1][0] + a * (p[k][0] - p[k - 1][0]), p[k - 1][1] + a * (p[k][1] - p[k - 1][1]),
          p[k - 1][2] + a * (p[k][2] - p[k - 1][2])};
}

Quaternion ToolTimeline::Path::rotation_at(double time) const {
  if (time <= t.front()) return r.front();
  if (time >= t.back()) return r.back();
  const size_t k = static_cast<size_t>(std::upper_bound(t.begin(), t.end(), time) - t.begin());
  return slerp(r[k - 1], r[k], (time - t[k - 1]) / (t[k] - t[k - 1]));
}

ToolTimeline::ToolTimeline(const std::vector<ToolAction>& tools, const std::vector<double>& rest, const Vec3& origin,
                           const std::function<void(const std::string&)>& note, const std::string& where) {
  const RestBounds bounds = bounds_of(rest);
  for (const ToolAction& spec : tools) {
    Tool tool;
    tool.spec = spec;
    Path& r = tool.path;
    for (const auto& k : spec.path) {
      Vec3 p = k.point.value;
      if (k.point.kind == PointSpec::Kind::position_mm) p = {p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]};
      if (k.point.kind == PointSpec::Kind::at_fraction) p = bounds.at(p);
      if (k.point.kind == PointSpec::Kind::offset_mm) p = {r.p.front()[0] + p[0], r.p.front()[1] + p[1], r.p.front()[2] + p[2]};
      r.t.push_back(k.t);
      r.p.push_back(p);
      r.r.push_back(k.rotation ? *k.rotation : r.r.empty() ? kIdentityRotation : r.r.back());
    }
    if (spec.acts() == ToolPrimitive::stitch) {
      resolve_stitches(spec, rest, origin, where, tool.stitch_points, tool.stitch_fields);
      r.t = {spec.start_s};
      r.p = {tool.stitch_points.front()[0]};
      r.r = {kIdentityRotation};
    }
    if (spec.acts() == ToolPrimitive::push_shape) tool.instrument = load_instrument(spec.instrument_mesh, spec.instrument_spacing_mm, note);
    if (spec.snap_to_tissue) {
      // The nearest rest particle to the first keyframe (lowest id on ties): the whole path moves by the
      // difference, so the tool starts on tissue whatever the bounding box looks like.
      double best = 1e300;
      size_t bi = 0;
      for (size_t i = 0; i < rest.size(); i += 3) {
        const double d = std::pow(rest[i] - r.p[0][0], 2) + std::pow(rest[i + 1] - r.p[0][1], 2) + std::pow(rest[i + 2] - r.p[0][2], 2);
        if (d < best) {
          best = d;
          bi = i;
        }
      }
      const Vec3 shift{rest[bi] - r.p[0][0], rest[bi + 1] - r.p[0][1], rest[bi + 2] - r.p[0][2]};
      for (auto& p : r.p) p = {p[0] + shift[0], p[1] + shift[1], p[2] + shift[2]};
      if (note) note(spec.label + ": path snapped to tissue by " + std::to_string(std::sqrt(best)) + " mm");
    }
    tools_.push_back(std::move(tool));
  }
}

Vec3 ToolTimeline::position(size_t i, double t) const { return tools_[i].path.at(t); }

Quaternion ToolTimeline::orientation(size_t i, double t) const { return tools_[i].path.rotation_at(t); }

bool ToolTimeline::active(size_t i, double t) const {
  const ToolAction& spec = tools_[i].spec;
  return t >= spec.start_s - kWindowTolerance && t < spec.end_s;
}

bool ToolTimeline::idle(double t0, double t1) const {
  for (const Tool& tool : tools_) {
    if (tool.spec.end_s > t0 && tool.spec.start_s <= t1 + kWindowTolerance) return false;
  }
  return true;
}

void ToolTimeline::inputs(double t0, double t1, double min_sweep_mm, std::vector<ToolInput>& out) {
  out.resize(tools_.size());
  for (size_t i = 0; i < tools_.size(); ++i) {
    Tool& tool = tools_[i];
    const ToolAction& spec = tool.spec;
    ToolInput& in = out[i];
    in.acts = spec.acts();
    in.name = spec.kind();
    in.label = spec.label;
    in.radius_mm = spec.radius_mm;
    in.force_n = spec.force_n;
    in.blade_edge_mm = spec.blade_edge_mm;
    in.active = active(i, t1);
    in.centre = tool.path.at(t1);
    in.start_s = spec.start_s;
    in.start_centre = tool.path.at(spec.start_s);
    in.sweeps.clear();
    in.instrument = tool.instrument;
    in.orientation = tool.path.rotation_at(t1);
    in.end_s = spec.end_s;
    in.local_region_mm = spec.local_region_mm;
    in.grip = spec.grip;
    in.grip_stiffness_ratio = spec.grip_stiffness_ratio;
    in.grip_edge_mm = spec.grip_edge_mm;
    in.removal_rate_mm3_s = spec.removal_rate_mm3_s;
    if (spec.acts() == ToolPrimitive::stitch) {
      in.stitches = tool.stitch_points;
      in.stitch_fields = tool.stitch_fields;
      in.stitch_target_mm = spec.stitch_target_mm;
      in.stitch_stiffness_ratio = spec.stitch_stiffness_ratio;
    }
    if (spec.acts() == ToolPrimitive::separate) sweeps(tool, t0, t1, min_sweep_mm, in.sweeps);
  }
}

size_t ToolTimeline::add_tool(const ToolAction& spec, const Vec3& origin, const std::string& where) {
  if (spec.type == nullptr || !spec.type->live) {
    throw InputError(where, spec.label, std::string(spec.type ? spec.kind() : "a tool without a type") +
                                            " cannot be added while running (" + live_tool_names() + " can)");
  }
  if (spec.path.empty() || spec.snap_to_tissue) throw InputError(where, spec.label, "needs a first keyframe and no snap_to_tissue");
  if (!(spec.end_s > spec.start_s)) throw InputError(where, spec.label, "its window must end after it starts");
  Tool tool;
  tool.spec = spec;
  tool.spec.path.clear();
  tools_.push_back(std::move(tool));
  const size_t i = tools_.size() - 1;
  for (const Keyframe& k : spec.path) {
    if (k.point.kind != PointSpec::Kind::position_mm || k.rotation) {
      tools_.pop_back();
      throw InputError(where, spec.label, "keyframes added while running are LPS positions without a rotation");
    }
    add_keyframe(i, k.t, k.point.value, origin);
  }
  return i;
}

void ToolTimeline::add_keyframe(size_t i, double t, const std::array<double, 3>& lps, const Vec3& origin) {
  Tool& tool = tools_.at(i);
  Path& r = tool.path;
  if (!r.t.empty() && t < r.t.back()) {
    throw RuntimeError("tool timeline: " + tool.spec.label + ": keyframe at t = " + std::to_string(t) + " s before its last");
  }
  if (!r.t.empty() && t == r.t.back()) {
    r.t.pop_back();
    r.p.pop_back();
    r.r.pop_back();
    tool.spec.path.pop_back();
  }
  r.t.push_back(t);
  r.p.push_back(local(lps, origin));
  r.r.push_back(kIdentityRotation);
  Keyframe k;
  k.t = t;
  k.point = {PointSpec::Kind::position_mm, lps};
  tool.spec.path.push_back(k);
}

void ToolTimeline::set_end(size_t i, double end_s) {
  Tool& tool = tools_.at(i);
  if (!(end_s > tool.spec.start_s)) {
    throw RuntimeError("tool timeline: " + tool.spec.label + ": window would end at " + std::to_string(end_s) + " s, not after its start");
  }
  tool.spec.end_s = end_s;
}

ToolTimeline::SweepState ToolTimeline::sweep_state() const {
  SweepState state;
  state.reserve(tools_.size());
  for (const Tool& tool : tools_) state.push_back(tool.cut_from);
  return state;
}

void ToolTimeline::restore_sweeps(const SweepState& checkpoint) {
  for (size_t i = 0; i < tools_.size(); ++i) tools_[i].cut_from = i < checkpoint.size() ? checkpoint[i] : std::nullopt;
}

void ToolTimeline::sweeps(Tool& tool, double t0, double t1, double min_sweep_mm, std::vector<std::array<Vec3, 2>>& out) const {
  const ToolAction& spec = tool.spec;
  if (!tool.cut_from && t1 >= spec.start_s - kWindowTolerance && t1 < spec.end_s) tool.cut_from = std::max(spec.start_s, t0);
  while (tool.cut_from) {
    const double from = *tool.cut_from, to_end = std::min(t1, spec.end_s);
    double to = to_end;
    for (const double kt : tool.path.t) {
      if (kt > from && kt < to) to = kt;
    }
    const Vec3 c0 = tool.path.at(from), c1 = tool.path.at(to);
    const double moved = std::sqrt(std::pow(c1[0] - c0[0], 2) + std::pow(c1[1] - c0[1], 2) + std::pow(c1[2] - c0[2], 2));
    const bool at_end = t1 >= spec.end_s;
    if (moved < min_sweep_mm && to == to_end && !at_end) break;
    out.push_back({c0, c1});
    tool.cut_from = to;
    if (to == to_end) {
      if (at_end) tool.cut_from.reset();
      break;
    }
  }
}

}  // namespace ctsurg::sim
