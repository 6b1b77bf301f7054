#include "ctsurg/sim/fem/fem_tools.h"

#include "ctsurg/core/error.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace ctsurg::sim {

std::vector<int32_t> free_nodes_in_sphere(const FemModel& model, const std::vector<double>& u,
                                          const std::vector<uint8_t>& held_axes, const Vec3& centre, double radius) {
  const int64_t nn = model.node_count();
  if (u.size() != static_cast<size_t>(3 * nn)) throw InputError("fem tools", "displacements", "expected #N x 3");
  if (held_axes.size() != static_cast<size_t>(nn)) throw InputError("fem tools", "fixed", "expected one mask per node");
  const std::vector<double>& rest = model.nodes;
  std::vector<int32_t> ids;
  for (int64_t i = 0; i < nn; ++i) {
    double d = 0;
    for (size_t a = 0; a < 3; ++a) d += std::pow(rest[static_cast<size_t>(3 * i) + a] + u[static_cast<size_t>(3 * i) + a] - centre[a], 2);
    if (d < radius * radius && held_axes[static_cast<size_t>(i)] != kAllAxes) ids.push_back(static_cast<int32_t>(i));
  }
  return ids;
}

FemToolHolds::FemToolHolds(const FemModel& model, std::vector<uint8_t> held_axes, std::string where,
                           std::function<void(const std::string&)> note)
    : model_(model), held_axes_(std::move(held_axes)), where_(std::move(where)), note_(std::move(note)) {
  if (held_axes_.size() != static_cast<size_t>(model_.node_count())) throw InputError("fem tools", "fixed", "expected one mask per node");
}

FemToolHolds::Hold& FemToolHolds::hold(size_t tool) {
  if (holds_.size() <= tool) holds_.resize(tool + 1);
  return holds_[tool];
}

void FemToolHolds::nodes_added(const std::vector<int32_t>& parents) {
  for (const int32_t p : parents) held_axes_.push_back(held_axes_.at(static_cast<size_t>(p)));
  // A grip's elements may now use a copy of a node it covered: its nodes again from the model's tets,
  // a copy's capture and target its parent's.
  const int32_t before = static_cast<int32_t>(held_axes_.size() - parents.size());
  const size_t npe = static_cast<size_t>(model_.nodes_per_element());
  for (Hold& h : holds_) {
    FemGrip& g = h.grip;
    if (g.elements.empty()) continue;
    const FemGrip old = g;
    g.nodes.clear();
    for (const int32_t e : g.elements)
      for (size_t a = 0; a < npe; ++a) g.nodes.push_back(model_.tets[npe * static_cast<size_t>(e) + a]);
    std::sort(g.nodes.begin(), g.nodes.end());
    g.nodes.erase(std::unique(g.nodes.begin(), g.nodes.end()), g.nodes.end());
    g.element_nodes.clear();
    for (const int32_t e : g.elements)
      for (size_t a = 0; a < npe; ++a)
        g.element_nodes.push_back(static_cast<int32_t>(
            std::lower_bound(g.nodes.begin(), g.nodes.end(), model_.tets[npe * static_cast<size_t>(e) + a]) - g.nodes.begin()));
    g.captured.clear();
    g.target.clear();
    for (const int32_t n : g.nodes) {
      const int32_t original = n >= before ? parents[static_cast<size_t>(n - before)] : n;
      const size_t k = static_cast<size_t>(std::lower_bound(old.nodes.begin(), old.nodes.end(), original) - old.nodes.begin());
      if (k >= old.nodes.size() || old.nodes[k] != original) throw RuntimeError("fem tools: a grip's element gained a node after a cut");
      for (size_t c = 0; c < 3; ++c) {
        g.captured.push_back(old.captured[3 * k + c]);
        g.target.push_back(old.target[3 * k + c]);
      }
    }
  }
  if (!nodal_forces_.empty()) nodal_forces_.resize(3 * held_axes_.size(), 0.0);
  if (held_axes_.size() != static_cast<size_t>(model_.node_count())) {
    throw RuntimeError("fem tools: the model has " + std::to_string(model_.node_count()) + " nodes after a cut, the tools know " +
                       std::to_string(held_axes_.size()));
  }
}

bool FemToolHolds::engaged(size_t tool) const {
  return tool < holds_.size() && (!holds_[tool].nodes.empty() || !holds_[tool].grip.elements.empty());
}

const std::vector<int32_t>& FemToolHolds::held_nodes(size_t tool) const {
  static const std::vector<int32_t> none;
  if (tool >= holds_.size()) return none;
  return holds_[tool].grip.elements.empty() ? holds_[tool].nodes : holds_[tool].grip.nodes;
}

bool FemToolHolds::captures(const std::vector<ToolInput>& tools) const {
  for (size_t i = 0; i < tools.size(); ++i) {
    if (tools[i].acts != ToolPrimitive::hold && tools[i].acts != ToolPrimitive::load) continue;
    const bool held = i < holds_.size() && (engaged(i) || holds_[i].released);
    if (tools[i].active && !held) return true;
  }
  return false;
}

void FemToolHolds::update_grabs(const std::vector<ToolInput>& tools, double t, const std::vector<double>& u,
                                bool capture_at_start, std::vector<int32_t>& nodes, std::vector<double>& displacements) {
  nodes.clear();
  displacements.clear();
  for (size_t i = 0; i < tools.size(); ++i) {
    const ToolInput& tool = tools[i];
    if (tool.acts != ToolPrimitive::hold || tool.grip != HoldGrip::nodes) continue;
    Hold& g = hold(i);
    g.centre = tool.centre;
    if (g.nodes.empty() && !g.released && tool.active) {
      const double when = capture_at_start ? tool.start_s : t;
      const Vec3& centre = capture_at_start ? tool.start_centre : tool.centre;
      g.nodes = free_nodes_in_sphere(model_, u, held_axes_, centre, tool.radius_mm);
      if (g.nodes.empty()) {
        throw InputError(where_, tool.label, "grabs no free node at t = " + std::to_string(when) +
                                                 " s; move it onto the tissue or set snap_to_tissue: true");
      }
      g.captured_at = centre;
      g.captured_u.clear();
      for (const int32_t n : g.nodes) {
        for (int k = 0; k < 3; ++k) g.captured_u.push_back(u[static_cast<size_t>(3 * n + k)]);
      }
      if (note_) note_(tool.label + ": grabbed " + std::to_string(g.nodes.size()) + " nodes at t = " + std::to_string(when) + " s");
    }
    if (!g.nodes.empty() && !tool.active) {
      g.nodes.clear();
      g.released = true;
    }
    for (size_t k = 0; k < g.nodes.size(); ++k) {
      nodes.push_back(g.nodes[k]);
      const uint8_t held = held_axes_[static_cast<size_t>(g.nodes[k])];
      for (size_t a = 0; a < 3; ++a) {
        // A held axis stays where its support holds it (0); the grab moves the free ones.
        displacements.push_back((held >> a) & 1u ? 0.0 : g.captured_u[3 * k + a] + tool.centre[a] - g.captured_at[a]);
      }
    }
  }
  // A node that two grabs hold follows the later one (listed once: the solvers take a node set).
  last_.assign(static_cast<size_t>(model_.node_count()), -1);
  for (size_t k = 0; k < nodes.size(); ++k) last_[static_cast<size_t>(nodes[k])] = static_cast<int64_t>(k);
  size_t kept = 0;
  for (size_t k = 0; k < nodes.size(); ++k) {
    if (last_[static_cast<size_t>(nodes[k])] != static_cast<int64_t>(k)) continue;
    nodes[kept] = nodes[k];
    for (size_t a = 0; a < 3; ++a) displacements[3 * kept + a] = displacements[3 * k + a];
    ++kept;
  }
  nodes.resize(kept);
  displacements.resize(3 * kept);
}

void FemToolHolds::update_grips(const std::vector<ToolInput>& tools, double t, const std::vector<double>& u, bool capture_at_start,
                                std::vector<FemGrip>& grips) {
  grips.clear();
  for (size_t i = 0; i < tools.size(); ++i) {
    const ToolInput& tool = tools[i];
    if (tool.acts != ToolPrimitive::hold || tool.grip != HoldGrip::volume) continue;
    Hold& g = hold(i);
    g.centre = tool.centre;
    if (g.grip.elements.empty() && !g.released && tool.active) {
      const double when = capture_at_start ? tool.start_s : t;
      const Vec3& centre = capture_at_start ? tool.start_centre : tool.centre;
      const double edge = tool.grip_edge_mm > 0 ? tool.grip_edge_mm : tool.radius_mm / 4;
      if (!(tool.grip_stiffness_ratio > 0) || !(edge <= tool.radius_mm)) {
        throw InputError(where_, tool.label, "a volume grip needs grip_stiffness_ratio > 0 and grip_edge_mm in (0, radius]");
      }
      g.grip = fem_capture_grip(model_, u, centre, tool.radius_mm, edge, 1.0);
      if (g.grip.elements.empty()) {
        throw InputError(where_, tool.label, "grips no material at t = " + std::to_string(when) +
                                                 " s; move it onto the tissue or set snap_to_tissue: true");
      }
      // The penalty per volume: ratio x E / r^2 of the stiffest material it holds (E from mu and lambda).
      double e_max = 0;
      for (const int32_t e : g.grip.elements) {
        const LameParameters& l = model_.lame_of(e);
        e_max = std::max(e_max, l.mu * (3 * l.lambda + 2 * l.mu) / (l.lambda + l.mu));
      }
      const double k = tool.grip_stiffness_ratio * e_max / (tool.radius_mm * tool.radius_mm);
      for (double& m : g.grip.matrices) m *= k;
      g.captured_at = centre;
      if (note_) {
        note_(tool.label + ": gripped " + std::to_string(g.grip.volume_mm3) + " mm^3 of tissue (" + std::to_string(g.grip.elements.size()) +
              " elements, penalty " + std::to_string(k) + " uN/mm^4) at t = " + std::to_string(when) + " s");
      }
    }
    if (!g.grip.elements.empty() && !tool.active) {
      g.grip = FemGrip{};
      g.released = true;
    }
    if (g.grip.elements.empty()) continue;
    fem_grip_move(g.grip, {tool.centre[0] - g.captured_at[0], tool.centre[1] - g.captured_at[1], tool.centre[2] - g.captured_at[2]});
    grips.push_back(g.grip);
  }
}

void FemToolHolds::add_shared_force(const Hold& hold, const Vec3& force_n, std::vector<double>& out) const {
  const std::vector<int32_t>& nodes = hold.nodes;
  if (!hold.weights.empty()) {
    for (size_t k = 0; k < nodes.size(); ++k)
      for (size_t a = 0; a < 3; ++a) out[3 * static_cast<size_t>(nodes[k]) + a] += force_n[a] * 1e6 * hold.weights[k];  // N -> uN
    return;
  }
  for (size_t a = 0; a < 3; ++a) {
    // The component along axis a is shared by the nodes free in a (all of them unless some are held in a).
    size_t free_in_a = 0;
    for (const int32_t n : nodes) free_in_a += (held_axes_[static_cast<size_t>(n)] >> a) & 1u ? 0 : 1;
    if (free_in_a == 0) continue;
    const double share = 1e6 / static_cast<double>(free_in_a);  // N -> uN
    for (const int32_t n : nodes)
      if (!((held_axes_[static_cast<size_t>(n)] >> a) & 1u)) out[3 * static_cast<size_t>(n) + a] += force_n[a] * share;
  }
}

// The hold's nodes and weights from a grip captured at k = 1: m_a = sum over its elements of row a of
// their matrices (integral of w N_a N_b summed over b = integral of w N_a, the shape functions summing to
// one), normalised by their sum (the weighted volume). Empty when the grip covers nothing.
void FemToolHolds::spread_over_volume(const FemGrip& region, Hold& hold) {
  hold.nodes.clear();
  hold.weights.clear();
  if (region.elements.empty()) return;
  const size_t npe = static_cast<size_t>(model_.nodes_per_element());
  std::vector<double> m(region.nodes.size(), 0.0);
  for (size_t e = 0; e < region.elements.size(); ++e)
    for (size_t a = 0; a < npe; ++a) {
      double row = 0;
      for (size_t b = 0; b < npe; ++b) row += region.matrices[(e * npe + a) * npe + b];
      m[static_cast<size_t>(region.element_nodes[e * npe + a])] += row;
    }
  double total = 0;
  for (const double x : m) total += x;
  if (!(total > 0)) return;
  hold.nodes = region.nodes;
  hold.weights.resize(m.size());
  for (size_t k = 0; k < m.size(); ++k) hold.weights[k] = m[k] / total;
}

bool FemToolHolds::load(size_t tool, const std::vector<double>& u, const std::vector<double>* reactions, std::array<double, 6>& out) const {
  if (!engaged(tool)) return false;
  const Hold& h = holds_[tool];
  if (!h.grip.elements.empty()) {
    out = fem_grip_load(model_, h.grip, u, h.centre);
    return true;
  }
  // A force tool: the force it shares among its nodes (as update_forces shares it); a node grab: the
  // reactions its held components need.
  std::vector<double> shared;
  if (h.force) {
    shared.assign(u.size(), 0.0);
    add_shared_force(h, h.force_n, shared);
  } else if (reactions == nullptr || reactions->size() != u.size()) {
    return false;
  }
  out = fem_nodal_load(model_, h.nodes, u, h.force ? shared : *reactions, h.centre);
  return true;
}

bool FemToolHolds::update_forces(const std::vector<ToolInput>& tools, const std::vector<double>& u, bool capture_at_start) {
  bool changed = false;
  for (size_t i = 0; i < tools.size(); ++i) {
    const ToolInput& tool = tools[i];
    if (tool.acts != ToolPrimitive::load) continue;
    Hold& f = hold(i);
    f.centre = tool.centre;
    f.force_n = tool.force_n;
    if (f.nodes.empty() && !f.released && tool.active) {
      f.force = true;
      const Vec3& centre = capture_at_start ? tool.start_centre : tool.centre;
      if (tool.grip == HoldGrip::volume) {
        const double edge = tool.grip_edge_mm > 0 ? tool.grip_edge_mm : tool.radius_mm / 4;
        if (!(edge <= tool.radius_mm)) throw InputError(where_, tool.label, "a volume force needs grip_edge_mm in (0, radius]");
        spread_over_volume(fem_capture_grip(model_, u, centre, tool.radius_mm, edge, 1.0), f);
        if (f.nodes.empty()) {
          throw InputError(where_, tool.label,
                           "the force's sphere holds no material; move it onto the tissue or set snap_to_tissue: true");
        }
      } else {
        f.nodes = free_nodes_in_sphere(model_, u, held_axes_, centre, tool.radius_mm);
        if (f.nodes.empty()) {
          throw InputError(where_, tool.label,
                           "the force's sphere holds no free node; move it onto the tissue or set snap_to_tissue: true");
        }
      }
      if (note_) note_(tool.label + ": force shared by " + std::to_string(f.nodes.size()) + " nodes" + (f.weights.empty() ? "" : " by volume"));
      changed = true;
    }
    if (!f.nodes.empty() && !tool.active) {
      f.nodes.clear();
      f.weights.clear();
      f.released = true;
      changed = true;
    }
  }
  if (!changed) return false;
  nodal_forces_.clear();
  for (size_t i = 0; i < tools.size(); ++i) {
    if (tools[i].acts != ToolPrimitive::load || !engaged(i)) continue;
    const Hold& f = holds_[i];
    if (nodal_forces_.empty()) nodal_forces_.assign(static_cast<size_t>(3 * model_.node_count()), 0.0);
    add_shared_force(f, tools[i].force_n, nodal_forces_);
  }
  return true;
}

}  // namespace ctsurg::sim
