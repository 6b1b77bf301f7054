// Tests for mesh/include/ctsurg/mesh/degenerate_triangles.h: the definition on hand-made triangles
// (each case on both sides of its threshold); marching cubes of quantised random fields (values
// exactly at the isovalue on many nodes: coincident vertices, zero-width handles, zero-size specks)
// and of continuous random fields (slivers) cleaned to closed, consistently oriented 2-manifolds
// with no degenerate triangle, no vertex moved, the volume kept and the lattice tie still exact; a
// lone node at the isovalue dropped; open surfaces keep their border.
#include "ctsurg/mesh/degenerate_triangles.h"

#include "ctsurg/core/error.h"
#include "ctsurg/mesh/marching_cubes.h"
#include "surface_checks.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <set>
#include <tuple>

namespace {

using ctsurg::Degeneracy;
using ctsurg::SurfaceMesh;
using ctsurg::Volume;

// One triangle (0, 1, 2) with the given corners, in a mesh of cell size 1 mm.
SurfaceMesh triangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  SurfaceMesh m;
  for (const auto& p : {a, b, c})
    for (int i = 0; i < 3; ++i) m.vertices.push_back(static_cast<float>(p[i]));
  m.triangles = {0, 1, 2};
  return m;
}

Degeneracy of(const SurfaceMesh& m, double h = 1.0) { return ctsurg::triangle_degeneracy(m, 0, h); }

TEST(DegenerateTriangles, DefinitionOnBothSidesOfEachThreshold) {
  const Eigen::Vector3d o(100.0, -50.0, 20.0);
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX(), y = Eigen::Vector3d::UnitY();
  EXPECT_EQ(of(triangle(o, o + x, o + y)), Degeneracy::kNone);
  SurfaceMesh repeated = triangle(o, o + x, o + y);
  repeated.triangles = {0, 1, 0};
  EXPECT_EQ(of(repeated), Degeneracy::kRepeatedIndex);
  EXPECT_EQ(of(triangle(o, o + x, o)), Degeneracy::kCoincidentCorners);
  // Coincident in float32 although different in double: what the file holds is what counts.
  EXPECT_EQ(of(triangle(o, o + x, o + Eigen::Vector3d(1e-9, 0.0, 0.0))), Degeneracy::kCoincidentCorners);
  // Equilateral triangles of side s: area sqrt(3)/4 s^2 against 1e-6 h^2 (h = 1 mm, then 10 mm).
  const auto equilateral = [&](double s) {
    return triangle(o, o + s * x, o + s * (0.5 * x + std::sqrt(3.0) / 2.0 * y));
  };
  EXPECT_EQ(of(equilateral(1.4e-3)), Degeneracy::kTinyArea);
  EXPECT_EQ(of(equilateral(1.6e-3)), Degeneracy::kNone);
  EXPECT_EQ(of(equilateral(1.4e-2), 10.0), Degeneracy::kTinyArea);
  EXPECT_EQ(of(equilateral(1.6e-2), 10.0), Degeneracy::kNone);
  // Needles and caps with smallest angle 0.9 and 1.1 degrees.
  const auto needle = [&](double deg) {
    const double r = deg * std::numbers::pi / 180.0;
    return triangle(o, o + x, o + Eigen::Vector3d(std::cos(r), std::sin(r), 0.0));
  };
  EXPECT_EQ(of(needle(0.9)), Degeneracy::kSliver);
  EXPECT_EQ(of(needle(1.1)), Degeneracy::kNone);
  const auto cap = [&](double deg) {  // apex over the middle of the base: two angles of `deg`
    return triangle(o, o + 2.0 * x, o + x + std::tan(deg * std::numbers::pi / 180.0) * y);
  };
  EXPECT_EQ(of(cap(0.9)), Degeneracy::kSliver);
  EXPECT_EQ(of(cap(1.1)), Degeneracy::kNone);
  // The count, by case.
  SurfaceMesh all = triangle(o, o + x, o + y);
  all.vertices.insert(all.vertices.end(), all.vertices.begin(), all.vertices.begin() + 3);  // vertex 3 = vertex 0
  all.triangles.insert(all.triangles.end(), {0, 0, 1, 3, 1, 0, 0, 1, 2});
  const ctsurg::DegenerateTriangleCount n = ctsurg::count_degenerate_triangles(all, 1.0);
  EXPECT_EQ(n.repeated_index, 1);
  EXPECT_EQ(n.coincident_corners, 1);
  EXPECT_EQ(n.total(), 2);
  EXPECT_EQ(n.summary(), "2 (1 repeated index, 1 coincident corners, 0 tiny area, 0 sliver)");
  EXPECT_THROW(ctsurg::count_degenerate_triangles(all, 0.0), ctsurg::InputError);
  EXPECT_THROW(ctsurg::remove_degenerate_triangles(all, std::nan("")), ctsurg::InputError);
}

// A random field on an n^3 lattice of spacing (1, 1.3, 0.8) mm with a zero frame (so the surface is
// closed): values in {0, 1/4, ..., 1} when `quantised` (iso 0.5 hits nodes exactly), uniform in
// [0, 1] otherwise.
Volume<float> random_field(int64_t n, unsigned seed, bool quantised) {
  ctsurg::ImageGeometry g;
  g.dims = {n, n, n};
  g.spacing = Eigen::Vector3d(1.0, 1.3, 0.8);
  g.origin = Eigen::Vector3d(-40.0, 25.0, 130.0);
  Volume<float> f(g, 0.0f);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> q(0, 4);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int64_t k = 1; k + 1 < n; ++k)
    for (int64_t j = 1; j + 1 < n; ++j)
      for (int64_t i = 1; i + 1 < n; ++i) f(i, j, k) = quantised ? 0.25f * float(q(rng)) : u(rng);
  return f;
}

// The checks every cleaned surface must pass against the marching-cubes surface it came from.
void expect_clean(const SurfaceMesh& mc, const SurfaceMesh& m, double h, double volume_tolerance, const std::string& what) {
  EXPECT_EQ(ctsurg::test::manifold_problem(m), "") << what;
  EXPECT_EQ(ctsurg::count_degenerate_triangles(m, h).total(), 0) << what << ": "
                                                                   << ctsurg::count_degenerate_triangles(m, h).summary();
  const double v0 = ctsurg::test::enclosed_volume(mc), v1 = ctsurg::test::enclosed_volume(m);
  EXPECT_NEAR(v1, v0, volume_tolerance * std::abs(v0) + 1e-9) << what;
  // No vertex moved: every vertex is one of marching cubes', with its normal and its tie.
  std::map<std::tuple<float, float, float>, int64_t> mc_vertex;
  for (int64_t w = 0; w < mc.vertex_count(); ++w) {
    const auto i = static_cast<std::size_t>(3 * w);
    mc_vertex.emplace(std::make_tuple(mc.vertices[i], mc.vertices[i + 1], mc.vertices[i + 2]), w);
  }
  ASSERT_EQ(m.normals.size(), m.vertices.size()) << what;
  ASSERT_EQ(m.grid_weights.size(), 8 * static_cast<std::size_t>(m.vertex_count())) << what;
  for (int64_t v = 0; v < m.vertex_count(); ++v) {
    const auto i = static_cast<std::size_t>(v);
    const auto it = mc_vertex.find({m.vertices[3 * i], m.vertices[3 * i + 1], m.vertices[3 * i + 2]});
    ASSERT_NE(it, mc_vertex.end()) << what << ": vertex " << v << " moved";
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (int c = 0; c < 8; ++c)
      p += double(m.grid_weights[8 * i + static_cast<std::size_t>(c)]) *
           m.lattice.index_to_world(Eigen::Vector3d(m.grid_cell[3 * i] + (c & 1), m.grid_cell[3 * i + 1] + ((c >> 1) & 1),
                                                    m.grid_cell[3 * i + 2] + ((c >> 2) & 1)));
    ASSERT_LT((p - ctsurg::test::vertex(m, uint32_t(v))).norm(), 1e-4) << what << ": the tie of vertex " << v;
  }
}

TEST(DegenerateTriangles, QuantisedRandomFieldsCleanToClosedOrientedManifolds) {
  int64_t degenerate = 0, merged = 0, cut = 0, dropped = 0;
  for (const int64_t n : {5, 8, 12})
    for (unsigned seed = 0; seed < 40; ++seed) {
      const Volume<float> f = random_field(n, seed, true);
      const SurfaceMesh mc = ctsurg::marching_cubes(f, 0.5);
      ASSERT_EQ(ctsurg::test::manifold_problem(mc), "");
      SurfaceMesh m = mc;
      const double h = ctsurg::lattice_cell_mm(m);
      EXPECT_DOUBLE_EQ(h, 0.8);
      const ctsurg::DegenerateRemovalStats s = ctsurg::remove_degenerate_triangles(m, h);
      degenerate += s.before.total();
      merged += s.merged;
      cut += s.handles_cut;
      dropped += s.dropped_components;
      EXPECT_EQ(s.after.total(), 0);
      // Only zero-length edges here (values are 0, 1/4, ..., 1: vertices at nodes or mid-edges), so
      // the volume is kept to rounding.
      expect_clean(mc, m, h, 1e-9, "n " + std::to_string(n) + " seed " + std::to_string(seed));
    }
  // The fields exercise every step: coincident corners, merges, zero-width handles, specks.
  EXPECT_GT(degenerate, 1000);
  EXPECT_GT(merged, 500);
  EXPECT_GT(cut, 10);
  EXPECT_GT(dropped, 10);
}

TEST(DegenerateTriangles, ContinuousRandomFieldsLoseTheirSlivers) {
  int64_t slivers = 0, collapsed = 0;
  for (const int64_t n : {6, 10, 16})
    for (unsigned seed = 0; seed < 30; ++seed) {
      const SurfaceMesh mc = ctsurg::marching_cubes(random_field(n, 1000 + seed, false), 0.5);
      SurfaceMesh m = mc;
      const ctsurg::DegenerateRemovalStats s = ctsurg::remove_degenerate_triangles(m, 0.8);
      slivers += s.before.total();
      collapsed += s.collapsed + s.flipped;
      // Collapses move no vertex but drop some: the volume changes by the slivers' tiny wedges.
      expect_clean(mc, m, 0.8, 1e-3, "n " + std::to_string(n) + " seed " + std::to_string(seed));
    }
  EXPECT_GT(slivers, 20);
  EXPECT_GT(collapsed, 20);
}

TEST(DegenerateTriangles, ALoneNodeAtTheIsovalueIsDroppedAndTheRestKept) {
  ctsurg::ImageGeometry g;
  g.dims = {12, 10, 10};
  Volume<float> f(g, 0.0f);
  f(2, 5, 5) = 0.5f;  // alone, exactly at iso: a closed surface of zero size
  Volume<float> block(g, 0.0f);
  for (int64_t k = 3; k < 7; ++k)
    for (int64_t j = 3; j < 7; ++j)
      for (int64_t i = 6; i < 10; ++i) f(i, j, k) = block(i, j, k) = 0.9f;
  SurfaceMesh lone = ctsurg::marching_cubes(f, 0.5);
  const SurfaceMesh only_block = ctsurg::marching_cubes(block, 0.5);
  ASSERT_GT(lone.triangle_count(), only_block.triangle_count());
  const ctsurg::DegenerateRemovalStats s = ctsurg::remove_degenerate_triangles(lone, 1.0);
  EXPECT_EQ(s.dropped_components, 1);
  EXPECT_EQ(lone.triangle_count(), only_block.triangle_count());
  EXPECT_EQ(lone.vertex_count(), only_block.vertex_count());
  EXPECT_EQ(ctsurg::test::manifold_problem(lone), "");
  // Nothing but the speck: the surface becomes empty.
  Volume<float> speck(g, 0.0f);
  speck(5, 5, 5) = 0.5f;
  SurfaceMesh m = ctsurg::marching_cubes(speck, 0.5);
  ASSERT_GT(m.triangle_count(), 0);
  ctsurg::remove_degenerate_triangles(m, 1.0);
  EXPECT_EQ(m.triangle_count(), 0);
  EXPECT_EQ(m.vertex_count(), 0);
}

// Without the zero frame the surface is open where the field is inside on the lattice border: the
// border (edges of one triangle) stays where it was, no edge gets more than two triangles, and the
// few degenerate triangles left all touch the border.
TEST(DegenerateTriangles, OpenSurfacesKeepTheirBorder) {
  int64_t removed = 0, left = 0;
  for (unsigned seed = 0; seed < 20; ++seed) {
    Volume<float> f = random_field(8, 500 + seed, true);
    for (int64_t j = 0; j < 8; ++j)
      for (int64_t i = 0; i < 8; ++i) f(i, j, 0) = 0.25f * float((i * 7 + j * 3 + seed) % 5);
    const SurfaceMesh mc = ctsurg::marching_cubes(f, 0.5);
    SurfaceMesh m = mc;
    const ctsurg::DegenerateRemovalStats stats = ctsurg::remove_degenerate_triangles(m, 0.8);
    left += stats.after.total();
    removed += stats.before.total() - stats.after.total();
    const auto border = [](const SurfaceMesh& s, std::set<std::tuple<float, float, float>>& points) {
      std::map<std::pair<uint32_t, uint32_t>, int> directed;
      for (std::size_t t = 0; t < s.triangles.size(); t += 3)
        for (std::size_t c = 0; c < 3; ++c) ++directed[{s.triangles[t + c], s.triangles[t + (c + 1) % 3]}];
      for (const auto& [e, count] : directed) {
        if (count != 1) return false;  // a directed edge twice: non-manifold or flipped
        if (!directed.count({e.second, e.first}))
          for (const uint32_t v : {e.first, e.second})
            points.insert({s.vertices[3 * std::size_t{v}], s.vertices[3 * std::size_t{v} + 1], s.vertices[3 * std::size_t{v} + 2]});
      }
      return true;
    };
    std::set<std::tuple<float, float, float>> before, after;
    ASSERT_TRUE(border(mc, before));
    ASSERT_TRUE(border(m, after)) << seed;
    for (const auto& p : after) EXPECT_TRUE(before.count(p)) << seed << ": a border vertex that was not on the border";
    // What is left touches the border: two border stretches meeting at a node exactly at the
    // isovalue, which no collapse may join (it would pinch the border into a non-manifold vertex).
    for (int64_t t = 0; t < m.triangle_count(); ++t) {
      if (ctsurg::triangle_degeneracy(m, t, 0.8) == Degeneracy::kNone) continue;
      bool touches = false;
      for (std::size_t c = 0; c < 3; ++c) {
        const std::size_t v = m.triangles[3 * static_cast<std::size_t>(t) + c];
        touches = touches || after.count({m.vertices[3 * v], m.vertices[3 * v + 1], m.vertices[3 * v + 2]});
      }
      EXPECT_TRUE(touches) << seed << ": degenerate triangle " << t << " away from the border";
    }
  }
  EXPECT_GT(removed, 20 * left);
}

}  // namespace
