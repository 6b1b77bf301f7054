// Tests for ctsurg/sim/fem/fem_contact.h: a box split by a plane into two bodies (separate_bodies), one
// held, the other driven into it: with contact no node ends deeper than a stated tolerance in the other
// body and both keep their volumes; without, they pass through each other. Self-contact: the lips of a
// crack pressed together stay apart. Bodies by label, the boundary and its normals, and the options'
// checks.
#include "ctsurg/sim/fem/fem_contact.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/tet_mesh_file.h"
#include "ctsurg/sim/fem/fem_box_mesh.h"
#include "ctsurg/sim/fem/fem_cutting.h"
#include "ctsurg/sim/fem/fem_explicit_dynamics.h"
#include "fem_test_models.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ctsurg::sim {
namespace {

// Tet volume of the elements whose rest centroid satisfies `in`, at positions rest + u.
double volume_where(const FemModel& m, const std::vector<double>& u, const std::function<bool(const double*)>& in) {
  double v = 0;
  for (int32_t e = 0; e < m.tet_count(); ++e) {
    double c[3] = {0, 0, 0}, d[3][3];
    const int32_t* t = &m.tets[4 * static_cast<size_t>(e)];
    for (int k = 0; k < 4; ++k)
      for (int a = 0; a < 3; ++a) c[a] += 0.25 * m.nodes[3 * static_cast<size_t>(t[k]) + static_cast<size_t>(a)];
    if (!in(c)) continue;
    for (int k = 1; k < 4; ++k)
      for (int a = 0; a < 3; ++a) {
        const size_t i = 3 * static_cast<size_t>(t[k]) + static_cast<size_t>(a), o = 3 * static_cast<size_t>(t[0]) + static_cast<size_t>(a);
        d[k - 1][a] = m.nodes[i] + u[i] - m.nodes[o] - u[o];
      }
    v += (d[0][0] * (d[1][1] * d[2][2] - d[1][2] * d[2][1]) - d[0][1] * (d[1][0] * d[2][2] - d[1][2] * d[2][0]) +
          d[0][2] * (d[1][0] * d[2][1] - d[1][1] * d[2][0])) / 6;
  }
  return v;
}

struct TwoBodies {
  FemModel model;
  int64_t faces_separated = 0;
};

// An 8 x 2 x 2 mm box of 1 mm Kuhn cells split at x = 4 into two 4 mm cubes.
TwoBodies two_bodies() {
  TetMesh mesh = tet_mesh_of(fem_box_mesh({8, 2, 2}, {8, 2, 2}));
  TwoBodies b;
  b.faces_separated = separate_bodies(mesh, false, {HalfSpace{{4, 0, 0}, {1, 0, 0}}}).faces;
  b.model = build_fem_model(mesh, test::fem_material(FemLaw::neo_hookean, 3e4, 0.3));
  return b;
}

// The left body held at x = 0, the right one's far end (x = 8) driven 0.6 mm towards it (-x) over 1,400
// steps and held for 600 (a press under displacement control: frictionless contact under a force
// would let the right cube slide off the left one's face).
std::vector<double> press(const FemModel& m, bool contact, double* deepest, double* min_right_x) {
  FemDynamicsOptions o;
  o.mass_damping = 50;
  o.contact.enabled = contact;
  FemExplicitDynamics d(m, o);
  d.set_fixed_nodes(test::nodes_where(m, 0, 0.0));
  const std::vector<int32_t> end = test::nodes_where(m, 0, 8.0);
  for (int s = 0; s < 20; ++s) {
    const double push = -0.6 * std::min(1.0, (s + 1) / 14.0);
    std::vector<double> disp;
    for (size_t k = 0; k < end.size(); ++k) disp.insert(disp.end(), {push, 0, 0});
    d.set_prescribed(end, disp);
    d.step(100);
  }
  const std::vector<double> u = d.displacements();
  *deepest = contact ? d.contact()->deepest_penetration(m, d.raw_displacements().data()) : 0;
  *min_right_x = 1e9;
  std::vector<int32_t> piece;
  fem_mesh_pieces(m.tets, m.node_count(), piece);
  const int32_t right = piece[static_cast<size_t>(m.node_count() - 1)];  // the last node is a copy at x = 4: the right body's
  for (int32_t n = 0; n < m.node_count(); ++n)
    if (piece[static_cast<size_t>(n)] == right) *min_right_x = std::min(*min_right_x, m.nodes[3 * n] + u[3 * n]);
  return u;
}

TEST(FemContact, TwoBodiesPressedTogetherDoNotInterpenetrateAndKeepTheirVolumes) {
  const TwoBodies b = two_bodies();
  EXPECT_EQ(b.faces_separated, 2 * 2 * 2);  // two triangles per cell face on the 2 x 2 faces at x = 4
  EXPECT_EQ(b.model.node_count(), 9 * 3 * 3 + 9);
  FemContact probe(b.model, FemContactOptions{true, true, 0, 4, 1, 0});
  EXPECT_EQ(probe.bodies(), 2);
  EXPECT_EQ(probe.boundary_faces(), 2 * (2 * (8 * 2 + 8 * 2 + 2 * 2)) + 2 * 2 * 2 * 2);  // the box's and the two new faces
  double deepest = 0, min_x = 0;
  const std::vector<double> u = press(b.model, true, &deepest, &min_x);
  EXPECT_LT(deepest, 0.05);  // under half the detection distance (a tenth of the 1.14 mm mean edge)
  // The right body sits on the left one's face: the 0.6 mm press shared by the two (about 0.3 mm each).
  EXPECT_GT(min_x, 4 - 0.6);
  EXPECT_LT(min_x, 4 - 0.15);
  const auto left = [](const double* c) { return c[0] < 4; };
  const auto right = [](const double* c) { return c[0] > 4; };
  EXPECT_NEAR(volume_where(b.model, u, left), 16, 0.05 * 16);
  EXPECT_NEAR(volume_where(b.model, u, right), 16, 0.05 * 16);
  // Without contact the right body passes into the left one by the whole press.
  double none = 0, min_x_free = 0;
  press(b.model, false, &none, &min_x_free);
  EXPECT_LT(min_x_free, 4 - 0.55);
}

TEST(FemContact, TheLipsOfACrackPressedTogetherStayApart) {
  // A 6 x 2 x 4 mm bar held at x = 0 with a crack at x = 3 from its top down to z = 1 (one body still),
  // pushed towards the held end: the lips meet; with self-contact the right lip stays out of the left.
  FemModel m0 = test::fem_box_model(FemLaw::neo_hookean, {6, 2, 4}, {6, 2, 4}, 3e4, 0.3);
  std::vector<int32_t> tets = m0.tets, parents;
  std::vector<double> nodes = m0.nodes;
  FemTetSeparation sep(m0);
  for (const Triangle& t : {Triangle{{3.1, -1, 1.2}, {3.1, 5, 1.2}, {3.1, 5, 9}}, Triangle{{3.1, -1, 1.2}, {3.1, 5, 9}, {3.1, -1, 9}}}) {
    const FemCutResult r = sep.cut(tets, static_cast<int32_t>(nodes.size() / 3), nodes, t);
    for (const int32_t p : r.new_node_parent) {
      parents.push_back(p);
      nodes.insert(nodes.end(), {nodes[3 * p], nodes[3 * p + 1], nodes[3 * p + 2]});
    }
  }
  const FemModel m = build_fem_model(nodes, tets, m0.materials[0]);
  ASSERT_GT(m.node_count(), m0.node_count());
  // The lips' overlap: each split node's left twin (the original id: the left elements are the lower
  // ones) against its right copy; positive when the right lip passed into the left.
  const auto run = [&](bool self) {
    FemDynamicsOptions o;
    o.mass_damping = 50;
    o.gravity = {-2e5, 0, 0};
    o.contact.enabled = true;
    o.contact.self = self;
    FemExplicitDynamics d(m, o);
    d.set_fixed_nodes(test::nodes_where(m, 0, 0.0));
    EXPECT_EQ(d.contact()->bodies(), 1);
    d.step(1500);
    const std::vector<double> u = d.displacements();
    double overlap = -1e9;
    for (size_t k = 0; k < parents.size(); ++k) {
      const size_t left = static_cast<size_t>(parents[k]), right = static_cast<size_t>(m0.node_count()) + k;
      overlap = std::max(overlap, (m.nodes[3 * left] + u[3 * left]) - (m.nodes[3 * right] + u[3 * right]));
    }
    return overlap;
  };
  const double with_self = run(true), without = run(false);
  EXPECT_LT(with_self, 0.05) << without;
  EXPECT_GT(without, 0.2) << with_self;
}

TEST(FemContact, BodiesByLabelAndChecks) {
  TetMesh mesh = tet_mesh_of(fem_box_mesh({4, 1, 1}, {4, 1, 1}));
  for (size_t e = 0; e < mesh.tet_labels.size(); ++e) mesh.tet_labels[e] = e < 12 ? 1 : 2;  // cells 0-1 and 2-3
  const BodySeparation sep = separate_bodies(mesh, true, {});
  EXPECT_EQ(sep.faces, 2);
  EXPECT_EQ(sep.nodes_split, 4);  // the 2 x 2 nodes of the face between the labels
  const FemModel m = build_fem_model(mesh, test::fem_material(FemLaw::linear));
  EXPECT_EQ(FemContact(m, FemContactOptions{true, true, 0, 4, 1, 0}).bodies(), 2);
  EXPECT_EQ(separate_bodies(mesh, false, {}).nodes_split, 0);
  // A gap: the slab's tets are taken out and the sides share no node.
  TetMesh gapped = tet_mesh_of(fem_box_mesh({8, 1, 1}, {8, 1, 1}));
  const BodySeparation g = separate_bodies(gapped, false, {HalfSpace{{4, 0, 0}, {1, 0, 0}}}, 1.2);
  EXPECT_EQ(g.tets_removed, 8);  // the tets of cells 3 and 4 whose centroids (x = 3.5, 3.75, 4.25, 4.5) are within 0.6 mm of x = 4
  EXPECT_EQ(g.nodes_split, 0);   // the tets left either side (centroids 3.25 and 4.75) share no node
  EXPECT_EQ(g.faces, 0);
  EXPECT_EQ(FemContact(build_fem_model(gapped, test::fem_material(FemLaw::linear)), FemContactOptions{true, true, 0, 4, 1, 0}).bodies(), 2);
  EXPECT_THROW(separate_bodies(mesh, false, {HalfSpace{{0, 0, 0}, {0, 0, 0}}}), InputError);
  EXPECT_THROW(FemContact(m, FemContactOptions{true, true, -1, 4, 1, 0}), InputError);
  EXPECT_THROW(FemContact(m, FemContactOptions{true, true, 0, 0, 1, 0}), InputError);
  EXPECT_THROW(FemContact(m, FemContactOptions{true, true, 0, 4, 0, 0}), InputError);
}

// Two unit cubes of 6 tets, the second moved by `offset`: two bodies of one model (no shared node).
FemModel two_cubes(const std::array<double, 3>& offset) {
  TetMesh mesh = tet_mesh_of(fem_box_mesh({1, 1, 1}, {1, 1, 1}));
  const size_t nodes = mesh.nodes.size() / 3, tets = mesh.tets.size();
  for (size_t n = 0; n < nodes; ++n)
    for (size_t a = 0; a < 3; ++a) mesh.nodes.push_back(mesh.nodes[3 * n + a] + offset[a]);
  for (size_t t = 0; t < tets; ++t) mesh.tets.push_back(mesh.tets[t] + static_cast<int32_t>(nodes));
  mesh.tet_labels.resize(mesh.tets.size() / 4, 1);
  return build_fem_model(mesh, test::fem_material(FemLaw::linear));
}

// Inside or outside is decided by the other body's nearest feature. The second cube's corner at
// (0.99, 1.02, 0.5), beside the first cube's convex top edge, lies behind the plane of the first cube's
// x = 1 face (its closest point on that face is on the edge, 0.022 mm away) yet outside it, 0.02 mm above
// the top face: no contact, and the two cubes do not overlap. (The rule taken from a face's plane alone
// pushed such nodes; on the kidney pressed into the liver it inverted elements within 0.1 s.) Moved
// 0.03 mm into the first cube instead, the corner is inside and pushed out.
TEST(FemContact, ANodeBesideAConvexEdgeIsOutsideAndANodeBehindAFaceIsInside) {
  const FemModel beside = two_cubes({0.99, 1.02, -0.5});
  FemContact a(beside, FemContactOptions{true, false, 0.1, 4, 1, 0});
  ASSERT_EQ(a.bodies(), 2);
  std::vector<Real> u(beside.nodes.size(), 0), inv_mass(beside.nodes.size() / 3, 1);
  EXPECT_EQ(a.deepest_penetration(beside, u.data()), 0.0);
  EXPECT_EQ(a.resolve(beside, u.data(), inv_mass.data()), 0);
  for (const Real x : u) EXPECT_EQ(x, 0);

  const FemModel inside = two_cubes({0.97, 0.25, 0.25});  // the corner (0.97, 0.25, 0.25) 0.03 mm deep
  FemContact b(inside, FemContactOptions{true, false, 0.1, 4, 1, 0});
  std::fill(u.begin(), u.end(), Real{0});
  EXPECT_NEAR(b.deepest_penetration(inside, u.data()), 0.03, 1e-9);
  EXPECT_GE(b.resolve(inside, u.data(), inv_mass.data()), 1);
  EXPECT_LT(b.deepest_penetration(inside, u.data()), 1e-3);
}

}  // namespace
}  // namespace ctsurg::sim
