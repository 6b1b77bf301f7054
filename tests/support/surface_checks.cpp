#include "surface_checks.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <map>
#include <set>
#include <utility>

namespace ctsurg::test {

Eigen::Vector3d vertex(const SurfaceMesh& m, uint32_t v) {
  return {m.vertices[3 * std::size_t{v}], m.vertices[3 * std::size_t{v} + 1], m.vertices[3 * std::size_t{v} + 2]};
}

std::string manifold_problem(const SurfaceMesh& m) {
  std::map<std::pair<uint32_t, uint32_t>, int> directed;
  for (int64_t t = 0; t < m.triangle_count(); ++t) {
    const uint32_t* f = &m.triangles[static_cast<std::size_t>(3 * t)];
    if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) return "degenerate triangle " + std::to_string(t);
    for (int c = 0; c < 3; ++c) ++directed[{f[c], f[(c + 1) % 3]}];
  }
  for (const auto& [e, n] : directed) {
    if (n != 1) return "directed edge used " + std::to_string(n) + " times";
    const auto it = directed.find({e.second, e.first});
    if (it == directed.end()) return "edge " + std::to_string(e.first) + "-" + std::to_string(e.second) + " has one triangle";
  }
  return "";
}

double enclosed_volume(const SurfaceMesh& m) {
  double v = 0.0;
  for (int64_t t = 0; t < m.triangle_count(); ++t) {
    const uint32_t* f = &m.triangles[static_cast<std::size_t>(3 * t)];
    v += vertex(m, f[0]).dot(vertex(m, f[1]).cross(vertex(m, f[2]))) / 6.0;
  }
  return v;
}

double surface_area(const SurfaceMesh& m) {
  double a = 0.0;
  for (int64_t t = 0; t < m.triangle_count(); ++t) {
    const uint32_t* f = &m.triangles[static_cast<std::size_t>(3 * t)];
    a += 0.5 * (vertex(m, f[1]) - vertex(m, f[0])).cross(vertex(m, f[2]) - vertex(m, f[0])).norm();
  }
  return a;
}

int64_t euler_characteristic(const SurfaceMesh& m) {
  std::set<uint32_t> used(m.triangles.begin(), m.triangles.end());
  std::set<std::pair<uint32_t, uint32_t>> edges;
  for (std::size_t t = 0; t < m.triangles.size(); t += 3)
    for (std::size_t c = 0; c < 3; ++c) {
      const uint32_t a = m.triangles[t + c], b = m.triangles[t + (c + 1) % 3];
      edges.insert({std::min(a, b), std::max(a, b)});
    }
  return static_cast<int64_t>(used.size()) - static_cast<int64_t>(edges.size()) + m.triangle_count();
}

}  // namespace ctsurg::test
