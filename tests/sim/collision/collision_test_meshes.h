// Meshes and comparisons shared by the sim/collision tests: random triangle soups and tets, a structured
// triangulated plane, a tet box (fem_box_mesh), and exact record comparisons.
#pragma once

#include "ctsurg/sim/collision/vertex_tet_contacts.h"
#include "ctsurg/sim/collision/vertex_triangle_contacts.h"
#include "ctsurg/sim/fem/fem_box_mesh.h"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

namespace ctsurg::sim::collision_test {

// Vertices, triangles or tets, and their object ids.
struct Scene {
  std::vector<double> positions;        // #V x 3 mm
  std::vector<uint32_t> primitives;     // #P x corners
  std::vector<uint32_t> vertex_object;  // #V
  std::vector<uint32_t> primitive_object;  // #P
};

// `triangles` random triangles (edges about `size` mm) in a cube of side `extent` at `origin`, each on
// its own three vertices, objects 0 and 1 alternating; then `points` random loose vertices (object 2)
// in the same cube. Every 7th triangle is degenerate (collinear or with coincident corners).
inline Scene random_soup(int triangles, int points, double extent, double size, std::array<double, 3> origin,
                         uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1), d(-1, 1);
  Scene s;
  auto push = [&](double x, double y, double z, uint32_t object) {
    s.positions.insert(s.positions.end(), {x, y, z});
    s.vertex_object.push_back(object);
  };
  for (int t = 0; t < triangles; ++t) {
    const double cx = origin[0] + extent * u(rng), cy = origin[1] + extent * u(rng), cz = origin[2] + extent * u(rng);
    const uint32_t object = static_cast<uint32_t>(t % 2), first = static_cast<uint32_t>(s.positions.size() / 3);
    std::array<double, 9> c{};
    for (double& v : c) v = size * d(rng);
    if (t % 7 == 3) {  // collinear: c on the line through a and b
      for (int k = 0; k < 3; ++k) c[6 + k] = 2 * c[3 + k] - c[k];
    } else if (t % 7 == 5) {  // two coincident corners
      for (int k = 0; k < 3; ++k) c[3 + k] = c[k];
    } else if (t % 14 == 6) {  // all three corners at one point
      for (int k = 0; k < 3; ++k) c[3 + k] = c[6 + k] = c[k];
    }
    for (int k = 0; k < 3; ++k) push(cx + c[3 * k], cy + c[3 * k + 1], cz + c[3 * k + 2], object);
    s.primitives.insert(s.primitives.end(), {first, first + 1, first + 2});
    s.primitive_object.push_back(object);
  }
  for (int p = 0; p < points; ++p)
    push(origin[0] + extent * u(rng), origin[1] + extent * u(rng), origin[2] + extent * u(rng), 2);
  return s;
}

// A plane z = z0 of n x n squares of side h, each split into two triangles (object 0): vertices on a grid.
inline Scene grid_plane(int n, double h, double z0) {
  Scene s;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      s.positions.insert(s.positions.end(), {i * h, j * h, z0});
      s.vertex_object.push_back(0);
    }
  const auto id = [n](int i, int j) { return static_cast<uint32_t>(i + (n + 1) * j); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      s.primitives.insert(s.primitives.end(), {id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      s.primitives.insert(s.primitives.end(), {id(i, j), id(i + 1, j + 1), id(i, j + 1)});
      s.primitive_object.insert(s.primitive_object.end(), {0, 0});
    }
  return s;
}

// The tets of a box (object 0, fem_box_mesh) as uint32.
inline Scene tet_box(std::array<int, 3> cells, std::array<double, 3> size, std::array<double, 3> origin) {
  const FemBoxMesh box = fem_box_mesh(cells, size, origin);
  Scene s;
  s.positions = box.nodes;
  s.vertex_object.assign(box.nodes.size() / 3, 0);
  s.primitives.assign(box.tets.begin(), box.tets.end());
  s.primitive_object.assign(box.tets.size() / 4, 0);
  return s;
}

// Appends a loose vertex (object `object`).
inline uint32_t add_point(Scene& s, double x, double y, double z, uint32_t object) {
  s.positions.insert(s.positions.end(), {x, y, z});
  s.vertex_object.push_back(object);
  return static_cast<uint32_t>(s.vertex_object.size() - 1);
}

// Exact equality of contact lists (every byte of every record: the same doubles).
template <class Record>
void expect_identical(const std::vector<Record>& a, const std::vector<Record>& b, const char* what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (std::size_t i = 0; i < a.size(); ++i)
    ASSERT_EQ(std::memcmp(&a[i], &b[i], sizeof(Record)), 0) << what << ": record " << i << " differs";
}

}  // namespace ctsurg::sim::collision_test
