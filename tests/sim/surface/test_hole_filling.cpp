// Tests for ctsurg/sim/surface/hole_filling.h: a hole punched in a closed surface is closed again with
// consistently oriented triangles (every edge in exactly two faces, each direction once); a single
// removed triangle comes back as itself; a planar loop is closed with exactly its area; an open surface's
// own boundary is never closed; texture-seam copies of a vertex are welded; and on the marching-cubes
// surface of a block cut through by a blade (surface_cutting.h) both sides are closed, with the enclosed
// volume that the cut leaves.
#include "ctsurg/sim/surface/hole_filling.h"

#include "block_surface.h"
#include "ctsurg/core/error.h"
#include "ctsurg/sim/surface/embedded_surface.h"
#include "ctsurg/sim/surface/surface_cutting.h"
#include "ctsurg/sim/surface/surface_measures.h"
#include "sim_test_models.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>

using namespace ctsurg;
using namespace ctsurg::sim;

namespace {

// Every undirected edge in exactly two faces, run once in each direction: closed and oriented.
bool closed_and_oriented(const std::vector<uint32_t>& t) {
  std::map<std::pair<uint32_t, uint32_t>, int> directed;
  for (size_t f = 0; f < t.size(); f += 3) {
    for (size_t e = 0; e < 3; ++e) ++directed[{t[f + e], t[f + (e + 1) % 3]}];
  }
  for (const auto& [edge, n] : directed) {
    if (n != 1) return false;
    const auto back = directed.find({edge.second, edge.first});
    if (back == directed.end() || back->second != 1) return false;
  }
  return true;
}

// A grid patch of (n + 1)^2 vertices in the plane z = 650 mm (spacing 1 mm), 2 n^2 triangles, normal +z.
void patch(int n, std::vector<float>& v, std::vector<uint32_t>& t) {
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) v.insert(v.end(), {float(i), float(j), 650.f});
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const uint32_t a = static_cast<uint32_t>(j * (n + 1) + i), b = a + 1, c = a + static_cast<uint32_t>(n + 1), d = c + 1;
      t.insert(t.end(), {a, b, d, a, d, c});
    }
  }
}

}  // namespace

TEST(HoleFilling, ARemovedInteriorTriangleComesBackAsItself) {
  std::vector<float> v;
  std::vector<uint32_t> t;
  patch(4, v, t);
  const std::vector<std::pair<uint32_t, uint32_t>> own = boundary_edges(t);
  EXPECT_EQ(own.size(), 16u);  // the patch's rim
  // Triangle 12 is (7, 8, 13), in cell (2, 1): interior (every edge shared with a neighbour).
  const std::vector<uint32_t> removed(t.begin() + 36, t.begin() + 39);
  t.erase(t.begin() + 36, t.begin() + 39);
  const auto loops = cut_hole_loops(t, own);
  ASSERT_EQ(loops.size(), 1u);
  const std::vector<uint32_t> fill = fill_cut_holes(t, v, own);
  ASSERT_EQ(fill.size(), 3u);
  // The same triangle, the same orientation (a cyclic rotation of its corners).
  bool same = false;
  for (size_t r = 0; r < 3; ++r) same |= fill[0] == removed[r] && fill[1] == removed[(r + 1) % 3] && fill[2] == removed[(r + 2) % 3];
  EXPECT_TRUE(same) << fill[0] << " " << fill[1] << " " << fill[2];
}

TEST(HoleFilling, APlanarHoleIsClosedWithItsAreaAndTheRimStaysOpen) {
  std::vector<float> v;
  std::vector<uint32_t> t;
  patch(6, v, t);
  const auto own = boundary_edges(t);
  // Remove the 2 x 2 interior cells at i, j = 2..3: a square hole of 4 mm^2 with 8 rim vertices.
  std::vector<uint32_t> kept;
  for (size_t f = 0; f < t.size(); f += 3) {
    const size_t cell = f / 6, i = cell % 6, j = cell / 6;
    if (i >= 2 && i <= 3 && j >= 2 && j <= 3) continue;
    kept.insert(kept.end(), t.begin() + static_cast<std::ptrdiff_t>(f), t.begin() + static_cast<std::ptrdiff_t>(f) + 3);
  }
  ASSERT_EQ(kept.size(), t.size() - 8 * 3);
  const auto loops = cut_hole_loops(kept, own);
  ASSERT_EQ(loops.size(), 1u);
  EXPECT_EQ(loops[0].size(), 8u);  // the centre vertex (3, 3) is left out: no new vertices, only the rim
  const std::vector<uint32_t> fill = fill_cut_holes(kept, v, own);
  EXPECT_EQ(fill.size(), 3u * 6);  // n - 2 triangles
  EXPECT_NEAR(surface_area(v, fill), 4.0, 1e-9);
  // Oriented like the patch (+z): the signed area's normal points up.
  for (size_t f = 0; f < fill.size(); f += 3) {
    const float* a = &v[3 * fill[f]];
    const float* b = &v[3 * fill[f + 1]];
    const float* c = &v[3 * fill[f + 2]];
    EXPECT_GE((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]), 0.0);
  }
  // The rim (the patch's own boundary) is not closed: only the hole's loop exists.
  std::vector<uint32_t> all = kept;
  all.insert(all.end(), fill.begin(), fill.end());
  EXPECT_EQ(boundary_edges(all), own);
  // A hole reaching the rim is an open chain there, and is left open.
  std::vector<uint32_t> corner(t.begin() + 6, t.end());  // cell (0, 0) removed: it touches the rim
  EXPECT_TRUE(fill_cut_holes(corner, v, own).empty());
}

TEST(HoleFilling, TriangulationIsMinimalAreaAndFansLongLoops) {
  // A regular hexagon at z = 650 mm: any triangulation of a convex planar polygon has its area.
  std::vector<float> v;
  std::vector<uint32_t> loop;
  for (uint32_t k = 0; k < 6; ++k) {
    v.insert(v.end(), {float(10 * std::cos(k * M_PI / 3)), float(10 * std::sin(k * M_PI / 3)), 650.f});
    loop.push_back(k);
  }
  const std::vector<uint32_t> t = triangulate_loop(loop, v);
  EXPECT_EQ(t.size(), 12u);
  EXPECT_NEAR(surface_area(v, t), 1.5 * std::sqrt(3.0) * 100, 1e-3);
  // A bent quad (two triangles folded along a diagonal): the cheaper diagonal is the one taken.
  const std::vector<float> q{0, 0, 0, 10, 0, 0, 10, 10, 8, 0, 10, 0};  // corner 2 lifted
  const std::vector<uint32_t> qt = triangulate_loop({0, 1, 2, 3}, q);
  const double a13 = surface_area(q, {0, 1, 3, 1, 2, 3}), a02 = surface_area(q, {0, 1, 2, 0, 2, 3});
  EXPECT_NEAR(surface_area(q, qt), std::min(a13, a02), 1e-9);
  EXPECT_LT(std::min(a13, a02), std::max(a13, a02) - 1);
  // Past kMaxDynamicLoop: a fan, still n - 2 triangles over the loop's vertices.
  std::vector<float> big;
  std::vector<uint32_t> big_loop;
  for (uint32_t k = 0; k < kMaxDynamicLoop + 5; ++k) {
    const double a = 2 * M_PI * k / (kMaxDynamicLoop + 5);
    big.insert(big.end(), {float(50 * std::cos(a)), float(50 * std::sin(a)), 0.f});
    big_loop.push_back(k);
  }
  EXPECT_EQ(triangulate_loop(big_loop, big).size(), 3 * (big_loop.size() - 2));
  EXPECT_THROW(triangulate_loop({0, 1, 99}, q), InputError);
}

TEST(HoleFilling, SeamCopiesAreWelded) {
  const std::vector<float> v{0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 0, 0, 5, 5, 5};
  const std::vector<uint32_t> w = weld_coincident(v);
  EXPECT_EQ(w, (std::vector<uint32_t>{0, 1, 2, 1, 4}));
}

// Two charts of a square (a texture seam along the diagonal 1-2, whose corners are repeated as 4 and
// 5): the seam is not a boundary; a cut removing one chart's triangle leaves a hole the filling closes
// across the seam.
TEST(HoleFilling, TextureSeamsAreNotHoles) {
  // A tetrahedron's surface (closed), with vertex 1 and 2 copied as 4 and 5 for the face (4, 3, 5).
  const std::vector<float> v{0, 0, 0, 10, 0, 0, 0, 10, 0, 0, 0, 10, 10, 0, 0, 0, 10, 0};
  const std::vector<uint32_t> t{0, 2, 1, 0, 1, 3, 0, 3, 2, 4, 5, 3};
  const std::vector<uint32_t> w = weld_coincident(v);
  EXPECT_EQ(boundary_edges(t).size(), 6u);  // raw ids: the seams look open
  const auto own = boundary_edges(t, w);
  EXPECT_TRUE(own.empty());
  // Cut away face (0, 1, 3): the hole is (0, 1, 3) in welded ids, its edge 1-3 on the seam's other chart.
  const std::vector<uint32_t> cut{0, 2, 1, 0, 3, 2, 4, 5, 3};
  const std::vector<uint32_t> fill = fill_cut_holes(cut, v, own, w);
  ASSERT_EQ(fill.size(), 3u);
  std::vector<uint32_t> sorted = fill;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(sorted, (std::vector<uint32_t>{0, 1, 3}));
}

// The marching-cubes surface of a 10 x 4 x 4 block of 2 mm cells, cut through at x = 21 mm by a blade:
// both sides' holes closed, every edge in two faces, and the volume is the uncut one less the slab of
// removed triangles (one cell wide), to 1 %.
TEST(HoleFilling, ABlockCutThroughStaysClosedOnBothSides) {
  const auto occ = test::block_occupancy(10, 4, 4, 2.0);
  const SpringGridModel model = build_spring_grid_model(occ, test::test_material());
  const SurfaceMesh mesh = test::block_surface(occ);
  ASSERT_TRUE(closed_and_oriented(mesh.triangles));
  const double v0 = enclosed_volume(mesh.vertices, mesh.triangles);
  for (const bool close : {false, true}) {
    EmbeddedSurface s(couple_surface(mesh, model.lattice, model.cells), mesh.triangles);
    s.set_close_cuts(close);
    const ParticleState state = model.make_state();
    int64_t removed = 0;
    for (const Triangle& blade : {Triangle{{21, -100, -100}, {21, 100, -100}, {21, 100, 300}},
                                  Triangle{{21, -100, -100}, {21, 100, 300}, {21, -100, 300}}}) {
      removed += s.cut(blade, mesh.vertices, state);
    }
    ASSERT_GT(removed, 0);
    EXPECT_EQ(s.close_cut_holes(mesh.vertices) > 0, close);
    EXPECT_EQ(closed_and_oriented(s.triangles()), close);
    if (!close) continue;
    // The removed band is the prism between the marching-cubes vertices at x = 20 and 22; each side's
    // cap is its planar section A, so the volume loses the slab 2 A = the caps' total area x 1 mm.
    const std::vector<uint32_t> caps(s.triangles().begin() + static_cast<std::ptrdiff_t>(s.triangles().size()) -
                                         3 * s.fill_triangle_count(), s.triangles().end());
    const double section = 0.5 * surface_area(mesh.vertices, caps);
    EXPECT_NEAR(section, 64.0, 8.0);  // 8 x 8 mm less the chamfered corners
    const double v = enclosed_volume(mesh.vertices, s.triangles());
    EXPECT_NEAR(v, v0 - 2 * section, 0.002 * v0) << "v0 " << v0 << " v " << v;
  }
}

// A partial incision (a blade 3 mm into the top of the block, as the heart incision): one hole, closed
// over the lips; the volume stays within 0.5 % of the uncut surface's.
TEST(HoleFilling, APartialIncisionIsClosedAndKeepsTheVolume) {
  const auto occ = test::block_occupancy(10, 6, 6, 2.0);
  const SpringGridModel model = build_spring_grid_model(occ, test::test_material());
  const SurfaceMesh mesh = test::block_surface(occ);
  const double v0 = enclosed_volume(mesh.vertices, mesh.triangles);
  EmbeddedSurface s(couple_surface(mesh, model.lattice, model.cells), mesh.triangles);
  s.set_close_cuts(true);
  const ParticleState state = model.make_state();
  // The top is z = 43 mm (cell centres 32 .. 42); the blade spans y = -16 .. -8 (inside the y = -19 .. -7
  // block), z = 40 .. 50, in the plane x = 21.
  for (const Triangle& blade : {Triangle{{21, -16, 40}, {21, -8, 40}, {21, -8, 50}}, Triangle{{21, -16, 40}, {21, -8, 50}, {21, -16, 50}}}) {
    s.cut(blade, mesh.vertices, state);
  }
  ASSERT_LT(s.triangles().size(), mesh.triangles.size());
  EXPECT_GT(s.close_cut_holes(mesh.vertices), 0);
  EXPECT_TRUE(closed_and_oriented(s.triangles()));
  EXPECT_NEAR(enclosed_volume(mesh.vertices, s.triangles()), v0, 0.005 * v0);
}
