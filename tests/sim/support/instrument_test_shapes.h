// Closed triangle meshes for the instrument tests: a box and an icosphere, outward wound, in mm.
#pragma once

#include "ctsurg/core/triangle_mesh_file.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

namespace ctsurg::sim::test {

// The box [lo, hi] as 12 outward triangles.
inline TriangleMesh box_mesh(const std::array<double, 3>& lo, const std::array<double, 3>& hi) {
  TriangleMesh m;
  for (int i = 0; i < 8; ++i) {
    m.vertices.insert(m.vertices.end(), {(i & 1) ? hi[0] : lo[0], (i & 2) ? hi[1] : lo[1], (i & 4) ? hi[2] : lo[2]});
  }
  // Faces of the cube with corners numbered by bits (x, y, z), counter-clockwise seen from outside.
  m.faces = {0, 2, 1, 1, 2, 3,  4, 5, 6, 5, 7, 6,  0, 1, 4, 1, 5, 4,  2, 6, 3, 3, 6, 7,  0, 4, 2, 2, 4, 6,  1, 3, 5, 3, 7, 5};
  return m;
}

// An icosphere of `radius` mm around `centre`, `levels` subdivisions of the icosahedron.
inline TriangleMesh icosphere(double radius, int levels, const std::array<double, 3>& centre = {0, 0, 0}) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<std::array<double, 3>> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                          {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<uint32_t, 3>> f = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                            {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                                            {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  const auto unit = [](std::array<double, 3> p) {
    const double n = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    return std::array<double, 3>{p[0] / n, p[1] / n, p[2] / n};
  };
  for (auto& p : v) p = unit(p);
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    const auto middle = [&](uint32_t a, uint32_t b) {
      const auto key = std::minmax(a, b);
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back(unit({v[a][0] + v[b][0], v[a][1] + v[b][1], v[a][2] + v[b][2]}));
      return mid[key] = static_cast<uint32_t>(v.size() - 1);
    };
    std::vector<std::array<uint32_t, 3>> g;
    for (const auto& tri : f) {
      const uint32_t a = middle(tri[0], tri[1]), b = middle(tri[1], tri[2]), c = middle(tri[2], tri[0]);
      g.insert(g.end(), {{tri[0], a, c}, {tri[1], b, a}, {tri[2], c, b}, {a, b, c}});
    }
    f = g;
  }
  TriangleMesh m;
  for (const auto& p : v) m.vertices.insert(m.vertices.end(), {centre[0] + radius * p[0], centre[1] + radius * p[1], centre[2] + radius * p[2]});
  for (const auto& tri : f) m.faces.insert(m.faces.end(), tri.begin(), tri.end());
  return m;
}

}  // namespace ctsurg::sim::test
