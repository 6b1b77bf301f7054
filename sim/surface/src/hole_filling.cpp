#include "ctsurg/sim/surface/hole_filling.h"

#include "ctsurg/core/error.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <string>

namespace ctsurg::sim {
namespace {

using Edge = std::pair<uint32_t, uint32_t>;

void check_triangles(const std::vector<uint32_t>& triangles) {
  if (triangles.size() % 3 != 0) throw InputError("hole filling", "triangles", "expected #F x 3 vertex ids");
}

// The boundary half-edges (u -> v, as their triangle runs them) in welded ids: the edges of the welded
// triangles used by one of them. Triangles whose welded corners repeat (a marching-cubes sliver between
// two vertices at one position) have no area and no edge of their own, and are skipped.
std::vector<Edge> boundary_half_edges(const std::vector<uint32_t>& triangles, const std::vector<uint32_t>& weld) {
  check_triangles(triangles);
  const auto id = [&](uint32_t v) {
    if (weld.empty()) return v;
    if (v >= weld.size()) throw InputError("hole filling", "triangles", "vertex id " + std::to_string(v) + " out of range");
    return weld[v];
  };
  std::map<Edge, std::pair<int, Edge>> uses;  // undirected -> (count, the directed half-edge)
  for (size_t f = 0; f < triangles.size(); f += 3) {
    const uint32_t c[3] = {id(triangles[f]), id(triangles[f + 1]), id(triangles[f + 2])};
    if (c[0] == c[1] || c[1] == c[2] || c[2] == c[0]) continue;
    for (size_t e = 0; e < 3; ++e) {
      const uint32_t u = c[e], v = c[(e + 1) % 3];
      auto& slot = uses[{std::min(u, v), std::max(u, v)}];
      ++slot.first;
      slot.second = {u, v};
    }
  }
  std::vector<Edge> out;
  for (const auto& [edge, use] : uses) {
    if (use.first == 1) out.push_back(use.second);
  }
  return out;
}

double triangle_area(const std::vector<float>& v, uint32_t a, uint32_t b, uint32_t c) {
  double e1[3], e2[3];
  for (size_t k = 0; k < 3; ++k) {
    e1[k] = double(v[3 * size_t(b) + k]) - v[3 * size_t(a) + k];
    e2[k] = double(v[3 * size_t(c) + k]) - v[3 * size_t(a) + k];
  }
  const double x = e1[1] * e2[2] - e1[2] * e2[1], y = e1[2] * e2[0] - e1[0] * e2[2], z = e1[0] * e2[1] - e1[1] * e2[0];
  return 0.5 * std::sqrt(x * x + y * y + z * z);
}

}  // namespace

std::vector<uint32_t> weld_coincident(const std::vector<float>& vertices) {
  const size_t nv = vertices.size() / 3;
  std::map<std::array<float, 3>, uint32_t> first;
  std::vector<uint32_t> weld(nv);
  for (size_t i = 0; i < nv; ++i) {
    const std::array<float, 3> p{vertices[3 * i], vertices[3 * i + 1], vertices[3 * i + 2]};
    weld[i] = first.emplace(p, static_cast<uint32_t>(i)).first->second;
  }
  return weld;
}

std::vector<std::pair<uint32_t, uint32_t>> boundary_edges(const std::vector<uint32_t>& triangles, const std::vector<uint32_t>& weld) {
  std::vector<Edge> out;
  for (const auto& [u, v] : boundary_half_edges(triangles, weld)) out.push_back({std::min(u, v), std::max(u, v)});
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::vector<uint32_t>> cut_hole_loops(const std::vector<uint32_t>& triangles, const std::vector<Edge>& own_boundary,
                                                  const std::vector<uint32_t>& weld) {
  // The filling runs each boundary edge v -> u opposite to its triangle's u -> v.
  std::map<uint32_t, std::vector<uint32_t>> out_edges;  // from -> to, sorted: deterministic walks
  std::map<Edge, bool> used;
  for (const auto& [u, v] : boundary_half_edges(triangles, weld)) {
    if (std::binary_search(own_boundary.begin(), own_boundary.end(), Edge{std::min(u, v), std::max(u, v)})) continue;
    out_edges[v].push_back(u);
    used[{v, u}] = false;
  }
  for (auto& [from, to] : out_edges) std::sort(to.begin(), to.end());
  const auto next_unused = [&](uint32_t from, uint32_t& to) {
    const auto it = out_edges.find(from);
    if (it == out_edges.end()) return false;
    for (const uint32_t t : it->second) {
      if (!used[{from, t}]) {
        to = t;
        return true;
      }
    }
    return false;
  };
  std::vector<std::vector<uint32_t>> loops;
  for (const auto& [start_edge, was_used] : std::map<Edge, bool>(used)) {
    if (used[start_edge]) continue;
    // Walk unused edges from start_edge; a vertex met again closes the loop between its two visits.
    std::vector<uint32_t> path{start_edge.first};
    std::map<uint32_t, size_t> at{{start_edge.first, 0}};
    uint32_t to = start_edge.second;
    used[start_edge] = true;
    while (true) {
      const auto seen = at.find(to);
      if (seen != at.end()) {
        loops.emplace_back(path.begin() + static_cast<std::ptrdiff_t>(seen->second), path.end());
        for (size_t k = seen->second + 1; k < path.size(); ++k) at.erase(path[k]);
        path.resize(seen->second + 1);
      } else {
        at[to] = path.size();
        path.push_back(to);
      }
      const uint32_t from = path.back();
      if (!next_unused(from, to)) break;  // closed (path back to one vertex) or an open chain: left open
      used[{from, to}] = true;
    }
  }
  // Degenerate two-vertex loops (an edge and its reverse both on the boundary) have no triangle.
  loops.erase(std::remove_if(loops.begin(), loops.end(), [](const auto& l) { return l.size() < 3; }), loops.end());
  return loops;
}

std::vector<uint32_t> triangulate_loop(const std::vector<uint32_t>& loop, const std::vector<float>& vertices) {
  const size_t n = loop.size();
  std::vector<uint32_t> out;
  if (n < 3) return out;
  for (const uint32_t v : loop) {
    if (3 * size_t(v) + 2 >= vertices.size()) throw InputError("hole filling", "loop", "vertex id " + std::to_string(v) + " out of range");
  }
  if (n > kMaxDynamicLoop) {
    for (size_t k = 1; k + 1 < n; ++k) out.insert(out.end(), {loop[0], loop[k], loop[k + 1]});
    return out;
  }
  // Barequet & Sharir / Liepa (2003, eq. 1 with the area weight): best[i][j] is the least area closing
  // the sub-polygon v_i .. v_j (with the chord j -> i), split[i][j] its apex k.
  std::vector<double> best(n * n, 0.0);
  std::vector<uint32_t> split(n * n, 0);
  for (size_t len = 2; len < n; ++len) {
    for (size_t i = 0; i + len < n; ++i) {
      const size_t j = i + len;
      double w = std::numeric_limits<double>::infinity();
      size_t arg = i + 1;
      for (size_t k = i + 1; k < j; ++k) {
        const double c = best[i * n + k] + best[k * n + j] + triangle_area(vertices, loop[i], loop[k], loop[j]);
        if (c < w) {  // strict: the lowest k on ties, so the result does not depend on rounding order
          w = c;
          arg = k;
        }
      }
      best[i * n + j] = w;
      split[i * n + j] = static_cast<uint32_t>(arg);
    }
  }
  // Unfold the splits: triangle (v_i, v_k, v_j) runs v_i -> v_k -> v_j, so every loop edge v_i -> v_i+1
  // and the closing v_n-1 -> v_0 keep the loop's direction.
  std::vector<std::pair<size_t, size_t>> stack{{0, n - 1}};
  while (!stack.empty()) {
    const auto [i, j] = stack.back();
    stack.pop_back();
    if (j < i + 2) continue;
    const size_t k = split[i * n + j];
    out.insert(out.end(), {loop[i], loop[k], loop[j]});
    stack.push_back({k, j});
    stack.push_back({i, k});
  }
  return out;
}

std::vector<uint32_t> fill_cut_holes(const std::vector<uint32_t>& triangles, const std::vector<float>& vertices,
                                     const std::vector<Edge>& own_boundary, const std::vector<uint32_t>& weld) {
  for (const uint32_t v : triangles) {
    if (3 * size_t(v) + 2 >= vertices.size()) throw InputError("hole filling", "triangles", "vertex id " + std::to_string(v) + " out of range");
  }
  std::vector<uint32_t> out;
  for (const auto& loop : cut_hole_loops(triangles, own_boundary, weld)) {
    const std::vector<uint32_t> t = triangulate_loop(loop, vertices);
    out.insert(out.end(), t.begin(), t.end());
  }
  return out;
}

}  // namespace ctsurg::sim
