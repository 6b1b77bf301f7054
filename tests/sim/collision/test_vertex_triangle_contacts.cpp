// Tests of sim/collision/vertex_triangle_contacts.h: the closest point on a triangle (Ericson 5.1.5)
// against its optimality condition and hand values, degenerate triangles, and the query against brute
// force on random and structured meshes (sizes, cell sizes, a 650 mm offset), points exactly on edges,
// the filters, determinism across thread counts, empty inputs and the argument checks.
#include "ctsurg/sim/collision/vertex_triangle_contacts.h"

#include "collision_test_meshes.h"
#include "ctsurg/core/error.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>

namespace ctsurg::sim {
namespace {

using collision_test::add_point;
using collision_test::expect_identical;
using collision_test::grid_plane;
using collision_test::random_soup;
using collision_test::Scene;

std::vector<VertexTriangleContact> triangle_query(const Scene& s, double distance, ContactPairs pairs = ContactPairs::between_objects,
                                         double cell = 0, int threads = 0) {
  ContactOptions o;
  o.pairs = pairs, o.cell_size = cell, o.threads = threads;
  return vertex_triangle_contacts(s.positions, s.primitives, s.vertex_object, s.primitive_object, distance, o);
}

std::vector<VertexTriangleContact> brute(const Scene& s, double distance, ContactPairs pairs = ContactPairs::between_objects) {
  return vertex_triangle_contacts_brute_force(s.positions, s.primitives, s.vertex_object, s.primitive_object, distance,
                                              pairs);
}

TEST(ClosestPointTriangle, HandValuesInEveryRegion) {
  const double a[3] = {0, 0, 0}, b[3] = {2, 0, 0}, c[3] = {0, 2, 0};
  struct Case {
    double p[3], bary[3];
  };
  const Case cases[] = {
      {{0.5, 0.5, 3}, {0.5, 0.25, 0.25}},  // face
      {{-1, -1, 1}, {1, 0, 0}},           // vertex a
      {{3, -1, 0}, {0, 1, 0}},            // vertex b
      {{-1, 3, 0}, {0, 0, 1}},            // vertex c
      {{1, -2, 0}, {0.5, 0.5, 0}},        // edge ab
      {{-2, 1, 0}, {0.5, 0, 0.5}},        // edge ac
      {{2, 2, 0}, {0, 0.5, 0.5}},         // edge bc
  };
  for (const Case& k : cases) {
    double bary[3];
    EXPECT_FALSE(closest_point_triangle(k.p, a, b, c, bary));
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(bary[i], k.bary[i], 1e-15) << k.p[0] << " " << k.p[1] << " " << i;
  }
  VertexTriangleContact r{};
  const double above[3] = {0.5, 0.5, 3}, below[3] = {0.5, 0.5, -3};
  ASSERT_TRUE(vertex_triangle_test(above, a, b, c, 3, r));
  EXPECT_DOUBLE_EQ(r.distance, 3);
  EXPECT_DOUBLE_EQ(r.signed_distance, 3);  // n = +z
  ASSERT_TRUE(vertex_triangle_test(below, a, b, c, 3, r));
  EXPECT_DOUBLE_EQ(r.signed_distance, -3);
  EXPECT_FALSE(vertex_triangle_test(below, a, b, c, 2.999, r));
}

// The closest point q of a convex set satisfies (p - q) . (x - q) <= 0 for every x in it; for a triangle
// it suffices at the corners. Checked, with |q| on the triangle, for random triangles and points.
TEST(ClosestPointTriangle, SatisfiesTheOptimalityCondition) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 20000; ++trial) {
    double x[4][3];
    for (auto& v : x)
      for (double& c : v) c = 10 * u(rng);
    if (trial % 2 == 1)
      for (auto& v : x) v[2] += 650;  // also far from the origin
    const double* p = x[3];
    double bary[3];
    closest_point_triangle(p, x[0], x[1], x[2], bary);
    double q[3];
    for (int k = 0; k < 3; ++k) q[k] = bary[0] * x[0][k] + bary[1] * x[1][k] + bary[2] * x[2][k];
    EXPECT_NEAR(bary[0] + bary[1] + bary[2], 1, 1e-12);
    for (double w : bary) ASSERT_GE(w, -1e-12) << trial;
    for (int corner = 0; corner < 3; ++corner) {
      double s = 0, scale = 0;
      for (int k = 0; k < 3; ++k) {
        s += (p[k] - q[k]) * (x[corner][k] - q[k]);
        scale += std::abs(p[k] - q[k]) * std::abs(x[corner][k] - q[k]);
      }
      ASSERT_LE(s, 1e-9 * (scale + 1)) << "trial " << trial << " corner " << corner;
    }
  }
}

TEST(ClosestPointTriangle, DegenerateTrianglesGiveTheClosestEdgePoint) {
  const double p[3] = {1, 2, 0.5};
  // Collinear (c between a and b), coincident corners, and a point triangle: finite, the distance to the
  // segment (or point) they span.
  const double a[3] = {0, 0, 0}, b[3] = {4, 0, 0}, mid[3] = {2, 0, 0};
  const double seg = std::sqrt(2.0 * 2.0 + 0.5 * 0.5);  // to the x axis at x = 1
  const double* triangles[][3] = {{a, b, mid}, {a, a, b}, {mid, a, b}, {a, a, a}};
  const double expected[] = {seg, seg, seg, std::sqrt(1 + 4 + 0.25)};
  for (int t = 0; t < 4; ++t) {
    VertexTriangleContact r{};
    ASSERT_TRUE(vertex_triangle_test(p, triangles[t][0], triangles[t][1], triangles[t][2], 100, r)) << t;
    EXPECT_NEAR(r.distance, expected[t], 1e-14) << t;
    EXPECT_EQ(r.signed_distance, r.distance) << t;
    for (double w : r.barycentric) EXPECT_TRUE(std::isfinite(w)) << t;
    for (double c : r.closest) EXPECT_TRUE(std::isfinite(c)) << t;
  }
}

TEST(VertexTriangleContacts, MatchesBruteForceOnRandomSoups) {
  for (const int triangles : {1, 40, 400}) {
    for (const double offset : {0.0, 650.0, -1200.0}) {
      const Scene s = random_soup(triangles, 300, 30, 2.0, {offset, -offset, offset}, triangles + 17);
      for (const double distance : {0.0, 0.4, 2.5}) {
        const auto reference = brute(s, distance);
        for (const double cell : {0.0, 0.5, 1.0, 12.0}) {
          SCOPED_TRACE(testing::Message() << triangles << " triangles, offset " << offset << ", d " << distance
                                          << ", cell " << cell);
          expect_identical(triangle_query(s, distance, ContactPairs::between_objects, cell), reference, "between objects");
          expect_identical(triangle_query(s, distance, ContactPairs::all, cell), brute(s, distance, ContactPairs::all), "all");
        }
        for (const auto& c : reference)
          for (double w : c.barycentric) ASSERT_TRUE(std::isfinite(w));
      }
    }
  }
  // The test must see contacts: the 400-triangle soup at 2.5 mm has many, with distances <= 2.5.
  const Scene s = random_soup(400, 300, 30, 2.0, {0, 0, 650}, 417);
  const auto c = triangle_query(s, 2.5);
  EXPECT_GT(c.size(), 100u);
  for (const auto& r : c) {
    EXPECT_LE(r.distance, 2.5);
    EXPECT_NE(s.vertex_object[r.vertex], s.primitive_object[r.triangle]);
    const double* p = s.positions.data() + 3 * r.vertex;
    EXPECT_NEAR(std::hypot(p[0] - r.closest[0], p[1] - r.closest[1], p[2] - r.closest[2]), r.distance, 1e-9);
  }
}

TEST(VertexTriangleContacts, PointsOnEdgesAndVerticesOfAPlane) {
  // A 6 x 6 grid of 1 mm squares at z = 650 (object 0); points (object 1) on the midpoints of interior
  // edges touch the two triangles of the edge, on interior grid nodes the six triangles around them,
  // at the centre of a square's diagonal the two triangles that share it.
  Scene s = grid_plane(6, 1.0, 650);
  const uint32_t horizontal = add_point(s, 2.5, 3, 650, 1);  // on a horizontal interior edge
  const uint32_t vertical = add_point(s, 3, 2.5, 650, 1);
  const uint32_t diagonal = add_point(s, 2.5, 2.5, 650, 1);
  const uint32_t node = add_point(s, 3, 3, 650, 1);
  const uint32_t corner = add_point(s, 6, 0, 650, 1);  // a corner node with one triangle
  const uint32_t above = add_point(s, 2.25, 2.75, 650.5, 1);  // 0.5 above
  const auto c = triangle_query(s, 1e-9);
  std::map<uint32_t, int> per_vertex;
  for (const auto& r : c) {
    ++per_vertex[r.vertex];
    EXPECT_LE(r.distance, 1e-9);
  }
  EXPECT_EQ(per_vertex[horizontal], 2);
  EXPECT_EQ(per_vertex[vertical], 2);
  EXPECT_EQ(per_vertex[diagonal], 2);
  EXPECT_EQ(per_vertex[node], 6);
  EXPECT_EQ(per_vertex[corner], 1);
  EXPECT_EQ(per_vertex.count(above), 0u);
  expect_identical(c, brute(s, 1e-9), "edges");
  // At 0.5 mm the point above meets its triangle's face only (distance 0.5, n = +z: positive side; the
  // other triangle of its square is 0.61 mm away).
  const auto far = triangle_query(s, 0.5 + 1e-9);
  int face = 0;
  for (const auto& r : far)
    if (r.vertex == above) {
      ++face;
      EXPECT_NEAR(r.distance, 0.5, 1e-9);
      EXPECT_NEAR(r.signed_distance, 0.5, 1e-9);
      EXPECT_NEAR(r.closest[0], 2.25, 1e-12);
      EXPECT_NEAR(r.closest[1], 2.75, 1e-12);
    }
  EXPECT_EQ(face, 1);
  expect_identical(far, brute(s, 0.5 + 1e-9), "0.5 mm");
}

TEST(VertexTriangleContacts, SelfContactExcludesIncidentTriangles) {
  // One mesh folded onto itself: a plane at z = 0 and a second sheet of the same object at z = 0.3.
  Scene s = grid_plane(5, 1.0, 0);
  const Scene top = grid_plane(5, 1.0, 0.3);
  const uint32_t base = static_cast<uint32_t>(s.vertex_object.size());
  s.positions.insert(s.positions.end(), top.positions.begin(), top.positions.end());
  s.vertex_object.insert(s.vertex_object.end(), top.vertex_object.begin(), top.vertex_object.end());
  for (uint32_t i : top.primitives) s.primitives.push_back(i + base);
  s.primitive_object.insert(s.primitive_object.end(), top.primitive_object.begin(), top.primitive_object.end());
  // One object: nothing between objects; with self-contact, each sheet's vertices touch the other sheet.
  EXPECT_TRUE(triangle_query(s, 0.35).empty());
  const auto self = triangle_query(s, 0.35, ContactPairs::all);
  ASSERT_FALSE(self.empty());
  const uint32_t triangles_per_sheet = static_cast<uint32_t>(top.primitive_object.size());
  for (const auto& r : self) {
    const uint32_t* f = s.primitives.data() + 3 * r.triangle;
    EXPECT_TRUE(f[0] != r.vertex && f[1] != r.vertex && f[2] != r.vertex);
    // A grid vertex is >= 1/sqrt(2) mm from its own sheet's non-incident triangles: contacts cross sheets.
    EXPECT_NE(r.vertex < base, r.triangle < triangles_per_sheet);
    EXPECT_NEAR(r.distance, 0.3, 1e-12);
  }
  // Every vertex of both sheets is 0.3 from the other sheet.
  std::vector<int> seen(s.vertex_object.size(), 0);
  for (const auto& r : self) seen[r.vertex] = 1;
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), static_cast<long>(seen.size()));
  expect_identical(self, brute(s, 0.35, ContactPairs::all), "self");
}

TEST(VertexTriangleContacts, ObjectFilter) {
  const Scene s = random_soup(300, 200, 15, 2.0, {0, 0, 0}, 99);
  const auto between = triangle_query(s, 1.0);
  const auto all = triangle_query(s, 1.0, ContactPairs::all);
  ASSERT_GT(between.size(), 0u);
  EXPECT_GT(all.size(), between.size());  // self-contacts within object 0 or 1 too
  size_t same = 0;
  for (const auto& r : between) EXPECT_NE(s.vertex_object[r.vertex], s.primitive_object[r.triangle]);
  for (const auto& r : all) same += s.vertex_object[r.vertex] == s.primitive_object[r.triangle];
  EXPECT_EQ(all.size() - same, between.size());
}

TEST(VertexTriangleContacts, SortedAndTheSameForAnyThreadCount) {
  const Scene s = random_soup(40000, 20000, 80, 1.5, {0, 0, 650}, 4);
  const auto one = triangle_query(s, 0.3, ContactPairs::all, 0, 1);
  ASSERT_GT(one.size(), 1000u);
  EXPECT_TRUE(std::is_sorted(one.begin(), one.end(), [](const auto& a, const auto& b) {
    return a.vertex != b.vertex ? a.vertex < b.vertex : a.triangle < b.triangle;
  }));
  for (std::size_t i = 1; i < one.size(); ++i)
    ASSERT_FALSE(one[i].vertex == one[i - 1].vertex && one[i].triangle == one[i - 1].triangle);  // no duplicates
  for (const int threads : {2, 3, 8}) expect_identical(triangle_query(s, 0.3, ContactPairs::all, 0, threads), one, "threads");
  expect_identical(triangle_query(s, 0.3, ContactPairs::all, 0.7, 2), one, "another cell size");
}

TEST(VertexTriangleContacts, EmptyInputs) {
  const std::vector<double> none;
  const std::vector<uint32_t> no_ids;
  EXPECT_TRUE(vertex_triangle_contacts(none, no_ids, no_ids, no_ids, 1.0).empty());
  const Scene points = random_soup(0, 50, 10, 1, {0, 0, 0}, 1);  // vertices, no triangles
  EXPECT_TRUE(triangle_query(points, 5.0, ContactPairs::all).empty());
}

TEST(VertexTriangleContacts, RejectsBadArguments) {
  const Scene s = random_soup(3, 3, 10, 1, {0, 0, 0}, 2);
  const auto call = [&](const std::vector<double>& x, const std::vector<uint32_t>& f, const std::vector<uint32_t>& vo,
                        const std::vector<uint32_t>& fo, double d, ContactOptions o = {}) {
    return vertex_triangle_contacts(x, f, vo, fo, d, o);
  };
  EXPECT_THROW(call(s.positions, s.primitives, s.vertex_object, s.primitive_object, -1), InputError);
  EXPECT_THROW(call(s.positions, s.primitives, s.vertex_object, s.primitive_object, std::nan("")), InputError);
  EXPECT_THROW(call(s.positions, s.primitives, {0, 1}, s.primitive_object, 1), InputError);
  EXPECT_THROW(call(s.positions, s.primitives, s.vertex_object, {0}, 1), InputError);
  auto bad_index = s.primitives;
  bad_index[4] = 1000;
  EXPECT_THROW(call(s.positions, bad_index, s.vertex_object, s.primitive_object, 1), InputError);
  auto bad_x = s.positions;
  bad_x[7] = INFINITY;
  EXPECT_THROW(call(bad_x, s.primitives, s.vertex_object, s.primitive_object, 1), InputError);
  ContactOptions negative_cell;
  negative_cell.cell_size = -2;
  EXPECT_THROW(call(s.positions, s.primitives, s.vertex_object, s.primitive_object, 1, negative_cell), InputError);
  ContactOptions threads;
  threads.threads = -1;
  EXPECT_THROW(call(s.positions, s.primitives, s.vertex_object, s.primitive_object, 1, threads), InputError);
  // cuda where it cannot run: refused (never the CPU silently).
  if (!backend_available(Backend::cuda)) {
    ContactOptions cuda;
    cuda.backend = Backend::cuda;
    try {
      call(s.positions, s.primitives, s.vertex_object, s.primitive_object, 1, cuda);
      ADD_FAILURE() << "cuda was not refused";
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), "backend");
      EXPECT_EQ(e.file(), "vertex triangle contacts");
    }
  }
}

}  // namespace
}  // namespace ctsurg::sim
