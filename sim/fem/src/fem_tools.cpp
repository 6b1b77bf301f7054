#include "ctsurg/sim/fem/fem_tools.h"

#include "ctsurg/core/error.h"

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
  if (!nodal_forces_.empty()) nodal_forces_.resize(3 * held_axes_.size(), 0.0);
  if (held_axes_.size() != static_cast<size_t>(model_.node_count())) {
    throw RuntimeError("fem tools: the model has " + std::to_string(model_.node_count()) + " nodes after a cut, the tools know " +
                       std::to_string(held_axes_.size()));
  }
}

bool FemToolHolds::engaged(size_t tool) const { return tool < holds_.size() && !holds_[tool].nodes.empty(); }

const std::vector<int32_t>& FemToolHolds::held_nodes(size_t tool) const {
  static const std::vector<int32_t> none;
  return tool < holds_.size() ? holds_[tool].nodes : none;
}

bool FemToolHolds::captures(const std::vector<ToolInput>& tools) const {
  for (size_t i = 0; i < tools.size(); ++i) {
    if (tools[i].acts != ToolPrimitive::hold && tools[i].acts != ToolPrimitive::load) continue;
    const bool held = i < holds_.size() && (!holds_[i].nodes.empty() || holds_[i].released);
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
    if (tool.acts != ToolPrimitive::hold) continue;
    Hold& g = hold(i);
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

bool FemToolHolds::update_forces(const std::vector<ToolInput>& tools, const std::vector<double>& u, bool capture_at_start) {
  bool changed = false;
  for (size_t i = 0; i < tools.size(); ++i) {
    const ToolInput& tool = tools[i];
    if (tool.acts != ToolPrimitive::load) continue;
    Hold& f = hold(i);
    if (f.nodes.empty() && !f.released && tool.active) {
      f.nodes = free_nodes_in_sphere(model_, u, held_axes_, capture_at_start ? tool.start_centre : tool.centre, tool.radius_mm);
      if (f.nodes.empty()) {
        throw InputError(where_, tool.label,
                         "the force's sphere holds no free node; move it onto the tissue or set snap_to_tissue: true");
      }
      if (note_) note_(tool.label + ": force shared by " + std::to_string(f.nodes.size()) + " nodes");
      changed = true;
    }
    if (!f.nodes.empty() && !tool.active) {
      f.nodes.clear();
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
    for (size_t a = 0; a < 3; ++a) {
      // The component along axis a is shared by the nodes free in a (all of them unless some are held in a).
      size_t free_in_a = 0;
      for (const int32_t n : f.nodes) free_in_a += (held_axes_[static_cast<size_t>(n)] >> a) & 1u ? 0 : 1;
      if (free_in_a == 0) continue;
      const double share = 1e6 / static_cast<double>(free_in_a);  // N -> uN
      for (const int32_t n : f.nodes)
        if (!((held_axes_[static_cast<size_t>(n)] >> a) & 1u)) nodal_forces_[static_cast<size_t>(3 * n) + a] += tools[i].force_n[a] * share;
    }
  }
  return true;
}

}  // namespace ctsurg::sim
