// Tests of sim/collision/vertex_tet_contacts.h: vertices inside the tets of a box mesh (fem_box_mesh,
// Kuhn's 6 tets per cell) against brute force and against the geometry (inside the box: >= 1 tet; outside:
// none; a point on a node: every tet of that node), barycentric reconstruction, self-contact exclusion,
// degenerate tets, determinism across thread counts, and the argument checks.
#include "ctsurg/sim/collision/vertex_tet_contacts.h"

#include "collision_test_meshes.h"
#include "ctsurg/core/error.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace ctsurg::sim {
namespace {

using collision_test::add_point;
using collision_test::expect_identical;
using collision_test::Scene;
using collision_test::tet_box;

std::vector<VertexTetContact> query(const Scene& s, ContactPairs pairs = ContactPairs::between_objects, double cell = 0,
                                    int threads = 0) {
  ContactOptions o;
  o.pairs = pairs, o.cell_size = cell, o.threads = threads;
  return vertex_tet_contacts(s.positions, s.primitives, s.vertex_object, s.primitive_object, o);
}

// A 4 x 3 x 3 box of 2.5 mm cells at (-5, 20, 650) and random points (object 1) in and around it.
Scene box_with_points(int points, uint32_t seed) {
  Scene s = tet_box({4, 3, 3}, {10, 7.5, 7.5}, {-5, 20, 650});
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.2, 1.2);
  for (int p = 0; p < points; ++p) add_point(s, -5 + 10 * u(rng), 20 + 7.5 * u(rng), 650 + 7.5 * u(rng), 1);
  return s;
}

TEST(VertexTetContacts, RandomPointsInABoxMesh) {
  const Scene s = box_with_points(3000, 3);
  const auto c = query(s);
  expect_identical(c, vertex_tet_contacts_brute_force(s.positions, s.primitives, s.vertex_object, s.primitive_object,
                                                      ContactPairs::between_objects),
                   "brute force");
  std::vector<int> count(s.vertex_object.size(), 0);
  for (const auto& r : c) {
    ++count[r.vertex];
    const double* p = s.positions.data() + 3 * r.vertex;
    double sum = 0;
    for (int k = 0; k < 3; ++k) {
      double x = 0;
      for (int i = 0; i < 4; ++i) x += r.barycentric[i] * s.positions[3 * s.primitives[4 * r.tet + i] + k];
      EXPECT_NEAR(x, p[k], 1e-9);
    }
    for (double b : r.barycentric) {
      EXPECT_GE(b, -kDefaultInsideTolerance);
      sum += b;
    }
    EXPECT_NEAR(sum, 1, 1e-12);
  }
  const int64_t nodes = 5 * 4 * 4;
  int inside = 0;
  for (int64_t v = nodes; v < static_cast<int64_t>(count.size()); ++v) {
    const double* p = s.positions.data() + 3 * v;
    const bool in = p[0] > -5 && p[0] < 5 && p[1] > 20 && p[1] < 27.5 && p[2] > 650 && p[2] < 657.5;
    if (in) {
      EXPECT_GE(count[v], 1) << v;  // the tets tile the box
      ++inside;
    } else {
      EXPECT_EQ(count[v], 0) << v;
    }
  }
  EXPECT_GT(inside, 1000);
  // The box's own nodes are object 0: never their own tets' contacts.
  for (int64_t v = 0; v < nodes; ++v) EXPECT_EQ(count[v], 0);
}

TEST(VertexTetContacts, PointsOnNodesAreInEveryTetOfTheNode) {
  Scene s = tet_box({3, 3, 3}, {3, 3, 3}, {0, 0, 650});
  const int64_t nodes = static_cast<int64_t>(s.vertex_object.size());
  std::vector<uint32_t> copy(nodes);
  for (int64_t v = 0; v < nodes; ++v)
    copy[v] = add_point(s, s.positions[3 * v], s.positions[3 * v + 1], s.positions[3 * v + 2], 1);
  std::vector<int> incident(nodes, 0);
  for (uint32_t i : s.primitives) ++incident[i];
  std::vector<int> count(s.vertex_object.size(), 0);
  for (const auto& r : query(s)) ++count[r.vertex];
  for (int64_t v = 0; v < nodes; ++v) EXPECT_EQ(count[copy[v]], incident[v]) << v;
  EXPECT_EQ(*std::max_element(incident.begin(), incident.end()), 24);  // an interior node of Kuhn's split
  // A conforming mesh's nodes lie only in their own tets, which self-contact excludes: it adds nothing.
  Scene alone = tet_box({3, 3, 3}, {3, 3, 3}, {0, 0, 650});
  EXPECT_TRUE(query(alone, ContactPairs::all).empty());
  expect_identical(query(s, ContactPairs::all), query(s), "self adds nothing");
}

TEST(VertexTetContacts, SelfContactBetweenOverlappingPartsOfOneObject) {
  // Two boxes of one object overlapping by half a cell: with self-contact, the nodes of each inside the
  // other are found; between objects, nothing.
  Scene s = tet_box({2, 2, 2}, {2, 2, 2}, {0, 0, 0});
  const Scene b = tet_box({2, 2, 2}, {2, 2, 2}, {1.5, 0.25, 0.25});
  const uint32_t base = static_cast<uint32_t>(s.vertex_object.size());
  s.positions.insert(s.positions.end(), b.positions.begin(), b.positions.end());
  s.vertex_object.insert(s.vertex_object.end(), b.vertex_object.begin(), b.vertex_object.end());
  for (uint32_t i : b.primitives) s.primitives.push_back(i + base);
  s.primitive_object.insert(s.primitive_object.end(), b.primitive_object.begin(), b.primitive_object.end());
  EXPECT_TRUE(query(s).empty());
  const auto self = query(s, ContactPairs::all);
  ASSERT_FALSE(self.empty());
  const uint32_t tets_a = static_cast<uint32_t>(b.primitive_object.size());
  for (const auto& r : self) EXPECT_NE(r.vertex < base, r.tet < tets_a);  // always across the two boxes
  expect_identical(self,
                   vertex_tet_contacts_brute_force(s.positions, s.primitives, s.vertex_object, s.primitive_object,
                                                   ContactPairs::all),
                   "brute force");
}

TEST(VertexTetContacts, DegenerateTetsContainNothing) {
  Scene s;
  s.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0,  // flat: four corners in z = 0
                 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,  // a point
                 0.25, 0.25, 0};
  s.vertex_object = {0, 0, 0, 0, 0, 0, 0, 0, 1};
  s.primitives = {0, 1, 2, 3, 4, 5, 6, 7};
  s.primitive_object = {0, 0};
  EXPECT_TRUE(query(s).empty());
}

TEST(VertexTetContacts, TheSameForAnyThreadCountAndCellSize) {
  const Scene s = box_with_points(20000, 8);
  const auto one = query(s, ContactPairs::between_objects, 0, 1);
  ASSERT_GT(one.size(), 5000u);
  EXPECT_TRUE(std::is_sorted(one.begin(), one.end(), [](const auto& a, const auto& b) {
    return a.vertex != b.vertex ? a.vertex < b.vertex : a.tet < b.tet;
  }));
  for (const int threads : {2, 5}) expect_identical(query(s, ContactPairs::between_objects, 0, threads), one, "threads");
  for (const double cell : {0.3, 9.0}) expect_identical(query(s, ContactPairs::between_objects, cell, 2), one, "cell");
}

TEST(VertexTetContacts, RejectsBadArguments) {
  const Scene s = box_with_points(10, 1);
  ContactOptions o;
  EXPECT_THROW(vertex_tet_contacts(s.positions, s.primitives, s.vertex_object, s.primitive_object, o, -1e-3), InputError);
  EXPECT_THROW(vertex_tet_contacts(s.positions, s.primitives, s.vertex_object, s.primitive_object, o, 0.5), InputError);
  std::vector<uint32_t> three(s.primitives.begin(), s.primitives.begin() + 3);
  EXPECT_THROW(vertex_tet_contacts(s.positions, three, s.vertex_object, std::vector<uint32_t>{}, o), InputError);
  EXPECT_THROW(vertex_tet_contacts(s.positions, s.primitives, s.vertex_object, std::vector<uint32_t>{0}, o), InputError);
  EXPECT_TRUE(vertex_tet_contacts(std::vector<double>{}, std::vector<uint32_t>{}, std::vector<uint32_t>{},
                                  std::vector<uint32_t>{}, o)
                  .empty());
}

}  // namespace
}  // namespace ctsurg::sim
