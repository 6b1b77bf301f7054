// Uniform refinement of tet meshes (tet_mesh_refinement.h).
#include "ctsurg/mesh/tet_mesh_refinement.h"

#include "ctsurg/core/error.h"
#include "ctsurg/mesh/tet_mesh_import.h"
#include "ctsurg/mesh/tet_mesh_quality.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace ctsurg {

namespace {

constexpr const char* kWhere = "tet mesh refinement";
// The local edges of a tet, in the order their midpoints are numbered 4..9 below.
constexpr std::array<std::array<int, 2>, 6> kEdges{{{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}}};

uint64_t edge_key(int32_t a, int32_t b) {
  if (a > b) std::swap(a, b);
  return (static_cast<uint64_t>(static_cast<uint32_t>(a)) << 32) | static_cast<uint32_t>(b);
}

double squared_distance(const std::vector<double>& nodes, int32_t a, int32_t b) {
  double d = 0;
  for (int c = 0; c < 3; ++c) {
    const double x = nodes[3 * static_cast<size_t>(a) + c] - nodes[3 * static_cast<size_t>(b) + c];
    d += x * x;
  }
  return d;
}

double signed_volume6(const std::vector<double>& nodes, const std::array<int32_t, 4>& t) {
  const auto p = [&](int k, int c) { return nodes[3 * static_cast<size_t>(t[k]) + c]; };
  const double a[3] = {p(1, 0) - p(0, 0), p(1, 1) - p(0, 1), p(1, 2) - p(0, 2)};
  const double b[3] = {p(2, 0) - p(0, 0), p(2, 1) - p(0, 1), p(2, 2) - p(0, 2)};
  const double c[3] = {p(3, 0) - p(0, 0), p(3, 1) - p(0, 1), p(3, 2) - p(0, 2)};
  return a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
}

TetMesh refine_once(const TetMesh& in) {
  const size_t n = static_cast<size_t>(in.node_count()), t_count = static_cast<size_t>(in.tet_count());
  std::vector<uint64_t> edges;
  edges.reserve(6 * t_count);
  for (size_t t = 0; t < t_count; ++t) {
    for (const auto& e : kEdges) edges.push_back(edge_key(in.tets[4 * t + e[0]], in.tets[4 * t + e[1]]));
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  constexpr size_t kMax = static_cast<size_t>(std::numeric_limits<int32_t>::max());
  if (n + edges.size() > kMax || 8 * t_count > kMax) {
    throw InputError(kWhere, "tets", std::to_string(t_count) + " tets and " + std::to_string(n + edges.size()) +
                                         " nodes after refinement: more than int32 indices can number");
  }
  TetMesh out;
  out.nodes.resize(3 * (n + edges.size()));
  std::copy(in.nodes.begin(), in.nodes.end(), out.nodes.begin());
  for (size_t e = 0; e < edges.size(); ++e) {
    const size_t a = edges[e] >> 32, b = edges[e] & 0xffffffffu;
    // The midpoint as (a + b) / 2 with a < b: the same double whichever tet asks.
    for (size_t c = 0; c < 3; ++c) out.nodes[3 * (n + e) + c] = 0.5 * (in.nodes[3 * a + c] + in.nodes[3 * b + c]);
  }
  const auto midpoint = [&](int32_t a, int32_t b) {
    const uint64_t key = edge_key(a, b);
    return static_cast<int32_t>(n + static_cast<size_t>(std::lower_bound(edges.begin(), edges.end(), key) - edges.begin()));
  };
  out.tets.reserve(32 * t_count);
  out.tet_labels.reserve(8 * t_count);
  for (size_t t = 0; t < t_count; ++t) {
    // v[0..3] the corners, v[4..9] the midpoints of kEdges.
    std::array<int32_t, 10> v{};
    for (int k = 0; k < 4; ++k) v[static_cast<size_t>(k)] = in.tets[4 * t + static_cast<size_t>(k)];
    for (size_t e = 0; e < 6; ++e) v[4 + e] = midpoint(v[static_cast<size_t>(kEdges[e][0])], v[static_cast<size_t>(kEdges[e][1])]);
    enum { m01 = 4, m02, m03, m12, m13, m23 };
    std::vector<std::array<int, 4>> children = {
        {0, m01, m02, m03}, {m01, 1, m12, m13}, {m02, m12, 2, m23}, {m03, m13, m23, 3}};
    // The octahedron (m01, m02, m03, m12, m13, m23) split around its shortest diagonal (a, b): the four
    // tets (a, b, c_k, c_k+1) over the ring of the other four midpoints.
    const std::array<std::array<int, 6>, 3> split{{
        {m01, m23, m02, m03, m13, m12},  // diagonal m01-m23, ring m02 m03 m13 m12
        {m02, m13, m01, m03, m23, m12},  // diagonal m02-m13, ring m01 m03 m23 m12
        {m03, m12, m01, m02, m23, m13},  // diagonal m03-m12, ring m01 m02 m23 m13
    }};
    size_t best = 0;
    double shortest = std::numeric_limits<double>::infinity();
    for (size_t d = 0; d < 3; ++d) {
      const double l = squared_distance(out.nodes, v[static_cast<size_t>(split[d][0])], v[static_cast<size_t>(split[d][1])]);
      if (l < shortest) {
        shortest = l;
        best = d;
      }
    }
    const auto& s = split[best];
    for (int k = 0; k < 4; ++k) children.push_back({s[0], s[1], s[2 + k], s[2 + (k + 1) % 4]});
    for (const auto& c : children) {
      std::array<int32_t, 4> tet{v[static_cast<size_t>(c[0])], v[static_cast<size_t>(c[1])], v[static_cast<size_t>(c[2])],
                                 v[static_cast<size_t>(c[3])]};
      if (signed_volume6(out.nodes, tet) < 0) std::swap(tet[2], tet[3]);
      out.tets.insert(out.tets.end(), tet.begin(), tet.end());
      out.tet_labels.push_back(in.tet_labels[t]);
    }
  }
  out.mask_volume_mm3 = in.mask_volume_mm3;
  out.seed = in.seed;
  nlohmann::json criteria = nlohmann::json::object();
  if (!in.criteria.empty()) {
    criteria = nlohmann::json::parse(in.criteria, nullptr, false);
    if (!criteria.is_object()) criteria = nlohmann::json{{"original", in.criteria}};
  }
  criteria["refinements"] = criteria.value("refinements", 0) + 1;
  out.criteria = criteria.dump();
  compute_boundary_faces(out);
  out.quality = tet_mesh_quality(out.nodes, out.tets, in.quality.sliver_threshold_deg > 0 ? in.quality.sliver_threshold_deg : 10.0);
  return out;
}

}  // namespace

TetMesh refine_tet_mesh_uniformly(const TetMesh& mesh, int times) {
  if (times < 0) throw InputError(kWhere, "times", "must be >= 0, not " + std::to_string(times));
  validate_tet_mesh(mesh, kWhere);
  TetMesh out = mesh;
  for (int k = 0; k < times; ++k) out = refine_once(out);
  return out;
}

}  // namespace ctsurg
