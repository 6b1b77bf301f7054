// Tests for ctsurg/sim/fem/fem_cutting.h and the FEM engine's cuts: a blade through a box of Kuhn tets
// separates the faces between the elements it passes between and splits exactly the nodes on the cut
// (counted), keeps every element, its volume and the mass; a cut that stops inside the mesh separates
// faces without freeing anything; a corner cut off is a second piece; many random cuts keep every
// element positively oriented and run the same twice; in the engine, a beam cut through near its
// support falls (dynamic, no NaN, the guard quiet) while the uncut beam hangs, a static run told to
// place a freed piece says what to do, the surface follows the copies of its own tets, and a
// quadratic model is refused.
#include "ctsurg/sim/fem/fem_cutting.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/fem/fem_box_mesh.h"
#include "ctsurg/sim/fem/fem_engine.h"
#include "ctsurg/sim/surface/tet_embedding.h"
#include "fem_test_models.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace ctsurg::sim {
namespace {

// A blade plane x = x0 over the whole box (two triangles covering y, z in [-50, 50]).
std::array<Triangle, 2> plane_x(double x0, double lo = -50, double hi = 50) {
  return {Triangle{{x0, lo, lo}, {x0, hi, lo}, {x0, hi, hi}}, Triangle{{x0, lo, lo}, {x0, hi, hi}, {x0, lo, hi}}};
}

FemModel box(std::array<int, 3> cells = {6, 3, 3}, std::array<double, 3> size = {6, 3, 3}) {
  return test::fem_box_model(FemLaw::neo_hookean, cells, size, 3e4, 0.3);
}

TEST(FemCutting, AThroughCutSplitsTheNodesOnTheCutAndKeepsEveryElement) {
  // A plane between the element layers at x = 2.5 and 3.5 passes through the node layer x = 3: every
  // face between an element left of x = 3 and one right of it is separated, and the 4 x 4 nodes of the
  // layer are split once each. The mesh is then two pieces of the same total volume and mass.
  const FemModel m = box();
  FemTetSeparation sep(m);
  std::vector<int32_t> tets = m.tets;
  int64_t faces = 0;
  std::vector<int32_t> parents;
  std::vector<double> nodes = m.nodes;
  for (const Triangle& t : plane_x(3.0)) {
    const FemCutResult r = sep.cut(tets, m.node_count() + static_cast<int32_t>(parents.size()), nodes, t);
    faces += r.faces_separated;
    for (const int32_t p : r.new_node_parent) {
      parents.push_back(p);
      nodes.insert(nodes.end(), {nodes[3 * p], nodes[3 * p + 1], nodes[3 * p + 2]});
    }
  }
  EXPECT_EQ(parents.size(), 16u);
  for (const int32_t p : parents) EXPECT_NEAR(m.nodes[3 * static_cast<size_t>(p)], 3.0, 1e-12);  // only the cut layer
  EXPECT_EQ(faces, 2 * 3 * 3);  // two triangles per cell face on the 3 x 3 cell faces at x = 3
  const FemModel cut = build_fem_model(nodes, tets, m.materials[0]);
  EXPECT_EQ(cut.tet_count(), m.tet_count());
  EXPECT_NEAR(fem_total_volume(cut), fem_total_volume(m), 1e-9);
  EXPECT_NEAR(fem_total_mass(cut), fem_total_mass(m), 1e-12);
  std::vector<int32_t> piece;
  EXPECT_EQ(fem_mesh_pieces(tets, cut.node_count(), piece), 2);
  for (int32_t n = 0; n < cut.node_count(); ++n) {
    // Left of the cut is one piece, right of it the other.
    if (cut.nodes[3 * n] < 2.9) {
      EXPECT_EQ(piece[static_cast<size_t>(n)], piece[0]);
    }
    if (cut.nodes[3 * n] > 3.1) {
      EXPECT_NE(piece[static_cast<size_t>(n)], piece[0]);
    }
  }
  // The same blade again separates nothing new.
  EXPECT_EQ(sep.cut(tets, cut.node_count(), nodes, plane_x(3.0)[0]).faces_separated, 0);
}

TEST(FemCutting, ACutEndingInsideSeparatesFacesWithoutFreeingAPiece) {
  // The blade covers y < 1.5 only (half the box's depth): the faces it crosses are separated, the
  // nodes behind the crack front stay joined around it, the mesh stays one piece.
  const FemModel m = box();
  FemTetSeparation sep(m);
  std::vector<int32_t> tets = m.tets;
  int32_t n = m.node_count();
  int64_t faces = 0;
  std::vector<double> nodes = m.nodes;
  for (const Triangle& t : std::array<Triangle, 2>{Triangle{{3.2, -1, -1}, {3.2, 1.5, -1}, {3.2, 1.5, 9}},
                                                   Triangle{{3.2, -1, -1}, {3.2, 1.5, 9}, {3.2, -1, 9}}}) {
    const FemCutResult r = sep.cut(tets, n, nodes, t);
    faces += r.faces_separated;
    n += static_cast<int32_t>(r.new_node_parent.size());
    for (const int32_t p : r.new_node_parent) nodes.insert(nodes.end(), {nodes[3 * p], nodes[3 * p + 1], nodes[3 * p + 2]});
  }
  EXPECT_GT(faces, 0);
  std::vector<int32_t> piece;
  EXPECT_EQ(fem_mesh_pieces(tets, n, piece), 1);
  EXPECT_EQ(sep.faces_separated(), faces);
}

TEST(FemCutting, ACornerCutOffIsASecondPiece) {
  const FemModel m = box();
  FemTetSeparation sep(m);
  std::vector<int32_t> tets = m.tets;
  // An oblique plane cutting the corner x, y, z < 1.6 off.
  const Triangle t{{4.0, -0.5, -0.5}, {-0.5, 4.0, -0.5}, {-0.5, -0.5, 4.0}};
  const FemCutResult r = sep.cut(tets, m.node_count(), m.nodes, t);
  EXPECT_GT(r.faces_separated, 0);
  std::vector<int32_t> piece;
  EXPECT_EQ(fem_mesh_pieces(tets, m.node_count() + static_cast<int32_t>(r.new_node_parent.size()), piece), 2);
}

// Many random blades: every cut model is valid (build_fem_model refuses inverted or degenerate tets),
// the volume is kept, and the same cuts give the same mesh.
std::vector<int32_t> random_cuts(const FemModel& m, uint64_t seed, int32_t* nodes_out) {
  FemTetSeparation sep(m);
  std::vector<int32_t> tets = m.tets;
  std::vector<double> pos = m.nodes;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 7);
  for (int c = 0; c < 40; ++c) {
    const Triangle t{{u(rng), u(rng) / 2, u(rng) / 2}, {u(rng), u(rng) / 2, u(rng) / 2}, {u(rng), u(rng) / 2, u(rng) / 2}};
    const FemCutResult r = sep.cut(tets, static_cast<int32_t>(pos.size() / 3), pos, t);
    for (const int32_t p : r.new_node_parent) pos.insert(pos.end(), {pos[3 * p], pos[3 * p + 1], pos[3 * p + 2]});
  }
  const FemModel cut = build_fem_model(pos, tets, m.materials[0]);
  EXPECT_NEAR(fem_total_volume(cut), fem_total_volume(m), 1e-9);
  *nodes_out = cut.node_count();
  return tets;
}

TEST(FemCutting, ManyRandomCutsKeepAValidMeshAndAreDeterministic) {
  const FemModel m = box();
  int32_t n1 = 0, n2 = 0;
  const auto a = random_cuts(m, 3, &n1), b = random_cuts(m, 3, &n2);
  EXPECT_EQ(a, b);
  EXPECT_EQ(n1, n2);
  EXPECT_GT(n1, m.node_count());
  EXPECT_THROW(FemTetSeparation(build_quadratic_fem_model(fem_box_mesh({2, 1, 1}, {2, 1, 1}).nodes, fem_box_mesh({2, 1, 1}, {2, 1, 1}).tets,
                                                          test::fem_material(FemLaw::linear))),
               InputError);
}

ToolInput blade_across(double x0, const Vec3& from, const Vec3& to) {
  ToolInput b;
  b.acts = ToolPrimitive::separate;
  b.label = "tools[0] (cut)";
  b.active = true;
  b.blade_edge_mm = {0, 0, 20};
  b.centre = to;
  b.sweeps = {{from, to}};
  (void)x0;
  return b;
}

TEST(FemEngine, ABeamCutThroughNearItsSupportFalls) {
  // A 6 x 3 x 3 mm beam fixed at x = 0 under gravity (-z): uncut it sags a little; cut through at
  // x = 1 (a blade edge along z swept along y), the free part falls freely. Explicit dynamics: no NaN,
  // the guard quiet, the clock carried over the rebuild.
  const auto run = [](bool cut, double* tip_z, int64_t* nodes) {
    FemModel m = box();
    FemEngineOptions o;
    o.solver = FemSolver::dynamic;
    o.gravity = {0, 0, -9810};
    o.mass_damping = 5;
    o.where = "s.yaml";
    FemBoundaryConditions supports;
    supports.fixed_nodes = test::nodes_where(m, 0, 0.0);
    FemEngine e(std::move(m), std::move(supports), EmbeddedSurface(), {0, 0, 0}, o);
    const int32_t tip = static_cast<int32_t>(e.model().node_count() - 1);  // (6, 3, 3)
    ASSERT_TRUE(e.step({}, 200).stable);
    const double t_before = e.time();
    if (cut) {
      ASSERT_TRUE(e.step({blade_across(1, {1, -1, 1.5}, {1, 4, 1.5})}, 1).stable);
      EXPECT_GT(e.counts().nodes, 64);
      EXPECT_NEAR(e.time(), t_before + e.dt(), 1e-15);
      EXPECT_EQ(e.metrics().springs_cut, 2 * 3 * 3);  // faces separated
    }
    for (int k = 0; k < 20; ++k) ASSERT_TRUE(e.step({}, 200).stable);
    e.sync();
    std::vector<double> p;
    e.positions(p);
    for (const double v : p) ASSERT_TRUE(std::isfinite(v));
    *tip_z = p[3 * static_cast<size_t>(tip) + 2];
    *nodes = e.counts().nodes;
  };
  double hanging = 0, falling = 0;
  int64_t n_hanging = 0, n_falling = 0;
  run(false, &hanging, &n_hanging);
  run(true, &falling, &n_falling);
  EXPECT_EQ(n_hanging, 7 * 4 * 4);
  EXPECT_EQ(n_falling, 7 * 4 * 4 + 16);
  EXPECT_GT(hanging, 3 - 1.0);  // sags a little
  EXPECT_LT(falling, 3 - 5.0);  // fell (0.5 g^2 t: metres per second squared over ~0.1 s)
}

TEST(FemEngine, AStaticRunToldToPlaceAFreedPieceSaysWhatToDo) {
  FemModel m = box();
  FemEngineOptions o;
  o.solver = FemSolver::static_equilibrium;
  o.where = "s.yaml";
  FemBoundaryConditions supports;
  supports.fixed_nodes = test::nodes_where(m, 0, 0.0);
  FemEngine e(std::move(m), std::move(supports), EmbeddedSurface(), {0, 0, 0}, o);
  try {
    e.equilibrium({blade_across(1, {1, -1, 1.5}, {1, 4, 1.5})}, 0.1);
    ADD_FAILURE() << "a freed piece was accepted by the static solver";
  } catch (const InputError& err) {
    EXPECT_EQ(err.file(), "s.yaml");
    EXPECT_EQ(err.field(), "tools[0] (cut)");
    EXPECT_NE(std::string(err.what()).find("solver: dynamic or implicit"), std::string::npos) << err.what();
  }
  // A cut that frees nothing (half the depth) solves.
  FemModel m2 = box();
  FemBoundaryConditions s2;
  s2.fixed_nodes = test::nodes_where(m2, 0, 0.0);
  FemEngine e2(std::move(m2), std::move(s2), EmbeddedSurface(), {0, 0, 0}, o);
  EXPECT_NO_THROW(e2.equilibrium({blade_across(1, {3.2, -1, 1.5}, {3.2, 1.4, 1.5})}, 0.1));
}

TEST(FemEngine, TheSurfaceFollowsTheCopiesOfItsOwnTets) {
  // Two triangles across the top, each side of the cut at x = 3: after the cut and a fall of the free
  // end under gravity, the right triangle's vertices went down with the right piece, the left ones
  // stayed; the triangle spanning the cut is removed.
  FemModel m = box();
  const std::vector<float> v = {0.5f, 0.5f, 3.f, 2.5f, 0.5f, 3.f, 2.5f, 2.5f, 3.f,   // left
                                3.5f, 0.5f, 3.f, 5.5f, 0.5f, 3.f, 5.5f, 2.5f, 3.f,   // right
                                2.0f, 1.5f, 3.f};                                     // spans the cut with 3.5
  EmbeddedSurface s(embed_surface_in_tets(v, tet_mesh_of(fem_box_mesh({6, 3, 3}, {6, 3, 3})), 1.0), {0, 1, 2, 3, 4, 5, 6, 3, 5});
  FemEngineOptions o;
  o.solver = FemSolver::dynamic;
  o.gravity = {0, 0, -9810};
  o.where = "s.yaml";
  FemBoundaryConditions supports;
  supports.fixed_nodes = test::nodes_where(m, 0, 0.0);
  FemEngine e(std::move(m), std::move(supports), std::move(s), {0, 0, 0}, o);
  ASSERT_TRUE(e.step({blade_across(3, {3, -1, 1.5}, {3, 4, 1.5})}, 1).stable);
  EXPECT_EQ(e.triangles().size(), 6u);  // the spanning triangle is gone
  for (int k = 0; k < 20; ++k) ASSERT_TRUE(e.step({}, 200).stable);
  e.sync();
  std::vector<float> xyz;
  e.surface_vertices(xyz);
  EXPECT_GT(xyz[2], 2.0f);   // left: held near the support
  EXPECT_LT(xyz[14], 0.0f);  // right (vertex 4): fell with the free piece
}

}  // namespace
}  // namespace ctsurg::sim
