// Tests for mesh/include/ctsurg/mesh/tet_mesh_refinement.h: one tet into eight (corner tets of an
// eighth of the volume, the octahedron split at its shortest diagonal), a two-label mesh whose
// boundary and interface are kept face for face (conforming: every other face shared by two tets),
// the shape of repeated refinement bounded, deterministic output, and refusals.
#include "ctsurg/mesh/tet_mesh_refinement.h"

#include "ctsurg/core/error.h"
#include "ctsurg/mesh/tet_mesh_import.h"
#include "ctsurg/mesh/tet_mesh_quality.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <map>

namespace {

using ctsurg::TetMesh;

Eigen::Vector3d refined_node(const TetMesh& m, int32_t i) { return {m.nodes[3 * size_t(i)], m.nodes[3 * size_t(i) + 1], m.nodes[3 * size_t(i) + 2]}; }

double refined_tet_volume(const TetMesh& m, int64_t t) {
  const auto* c = &m.tets[4 * size_t(t)];
  return ctsurg::tet_signed_volume(refined_node(m, c[0]), refined_node(m, c[1]), refined_node(m, c[2]), refined_node(m, c[3]));
}

double boundary_area_mm2(const TetMesh& m, uint16_t outside) {
  double a = 0;
  for (int64_t f = 0; f < m.boundary_face_count(); ++f) {
    if (m.face_labels[2 * size_t(f) + 1] != outside) continue;
    const auto* c = &m.boundary_faces[3 * size_t(f)];
    a += 0.5 * (refined_node(m, c[1]) - refined_node(m, c[0])).cross(refined_node(m, c[2]) - refined_node(m, c[0])).norm();
  }
  return a;
}

// A skewed tet (not regular, so the three diagonals differ) and a cube of six tets, labels 1 and 2.
TetMesh skewed_tet() {
  TetMesh m;
  m.nodes = {0, 0, 0, 10, 0, 0, 2, 7, 0, 3, 2, 9};
  m.tets = {0, 1, 2, 3};
  m.tet_labels = {1};
  ctsurg::compute_boundary_faces(m);
  m.quality = ctsurg::tet_mesh_quality(m.nodes, m.tets);
  m.criteria = R"({"cell_size_mm":6.0})";
  return m;
}

TetMesh kuhn_cube() {
  TetMesh m;
  for (int k = 0; k < 8; ++k) m.nodes.insert(m.nodes.end(), {10.0 * (k & 1), 10.0 * ((k >> 1) & 1), 10.0 * ((k >> 2) & 1)});
  // The Kuhn split of the cube along its diagonal 0-7: six tets around it.
  const int paths[6][2] = {{1, 3}, {1, 5}, {2, 3}, {2, 6}, {4, 5}, {4, 6}};
  for (int p = 0; p < 6; ++p) {
    std::array<int32_t, 4> t{0, paths[p][0], paths[p][1], 7};
    if (ctsurg::tet_signed_volume(refined_node(m, t[0]), refined_node(m, t[1]), refined_node(m, t[2]), refined_node(m, t[3])) < 0) std::swap(t[2], t[3]);
    m.tets.insert(m.tets.end(), t.begin(), t.end());
    m.tet_labels.push_back(p < 3 ? 1 : 2);
  }
  ctsurg::compute_boundary_faces(m);
  m.quality = ctsurg::tet_mesh_quality(m.nodes, m.tets);
  return m;
}

}  // namespace

TEST(TetMeshRefinement, OneTetBecomesEightThatFillIt) {
  const TetMesh m = skewed_tet();
  const TetMesh r = ctsurg::refine_tet_mesh_uniformly(m);
  ASSERT_EQ(r.node_count(), 10);
  ASSERT_EQ(r.tet_count(), 8);
  EXPECT_EQ(r.tet_labels, std::vector<uint16_t>(8, 1));
  const double v = refined_tet_volume(m, 0);
  double sum = 0;
  for (int64_t t = 0; t < 8; ++t) {
    const double child = refined_tet_volume(r, t);
    EXPECT_GT(child, 0) << t;
    if (t < 4) {
      EXPECT_NEAR(child, v / 8, 1e-12 * v) << t;  // the corner tets: the parent halved
    }
    sum += child;
  }
  EXPECT_NEAR(sum, v, 1e-12 * v);
  EXPECT_EQ(r.quality.inverted, 0);
  EXPECT_NEAR(r.quality.volume_mm3, v, 1e-12 * v);
  // The parent's nodes first, then the midpoints; the skin is the parent's four faces in sixteen.
  for (int i = 0; i < 12; ++i) EXPECT_EQ(r.nodes[size_t(i)], m.nodes[size_t(i)]);
  EXPECT_EQ(r.boundary_face_count(), 16);
  EXPECT_NEAR(boundary_area_mm2(r, 0), boundary_area_mm2(m, 0), 1e-12 * boundary_area_mm2(m, 0));
  // The octahedron's four tets share the shortest diagonal.
  double shortest = 1e300;
  std::pair<int32_t, int32_t> diagonal;
  for (const auto& [a, b] : {std::pair{4, 9}, std::pair{5, 8}, std::pair{6, 7}}) {
    const double l = (refined_node(r, a) - refined_node(r, b)).norm();
    if (l < shortest) shortest = l, diagonal = {a, b};
  }
  for (int64_t t = 4; t < 8; ++t) {
    const auto* c = &r.tets[4 * size_t(t)];
    EXPECT_TRUE(std::count(c, c + 4, diagonal.first) == 1 && std::count(c, c + 4, diagonal.second) == 1) << t;
  }
  const nlohmann::json criteria = nlohmann::json::parse(r.criteria);
  EXPECT_EQ(criteria["refinements"], 1);
  EXPECT_EQ(criteria["cell_size_mm"], 6.0);
}

TEST(TetMeshRefinement, KeepsTheBoundaryAndTheInterfaceAndConforms) {
  const TetMesh m = kuhn_cube();
  const TetMesh r = ctsurg::refine_tet_mesh_uniformly(m, 2);
  EXPECT_EQ(r.tet_count(), 64 * m.tet_count());
  EXPECT_EQ(r.quality.inverted, 0);
  EXPECT_NEAR(r.quality.volume_mm3, 1000, 1e-9);
  // Every skin and interface face in 16 (twice four): a face that did not conform would add more.
  EXPECT_EQ(r.boundary_face_count(), 16 * m.boundary_face_count());
  EXPECT_NEAR(boundary_area_mm2(r, 0), 600, 1e-9);
  EXPECT_NEAR(boundary_area_mm2(r, 2), boundary_area_mm2(m, 2), 1e-9);  // the interface, label 1 inside
  EXPECT_GT(boundary_area_mm2(m, 2), 0);
  // Every face is held by one tet (the boundary) or two; the 125 nodes of a 4 x 4 x 4 lattice.
  std::map<std::array<int32_t, 3>, int> faces;
  for (int64_t t = 0; t < r.tet_count(); ++t) {
    const auto* c = &r.tets[4 * size_t(t)];
    for (int skip = 0; skip < 4; ++skip) {
      std::array<int32_t, 3> f{};
      for (int k = 0, j = 0; k < 4; ++k)
        if (k != skip) f[size_t(j++)] = c[k];
      std::sort(f.begin(), f.end());
      ++faces[f];
    }
  }
  int on_skin = 0;
  for (const auto& [f, n] : faces) {
    EXPECT_LE(n, 2);
    on_skin += n == 1;
  }
  EXPECT_EQ(on_skin, 16 * 12);
  EXPECT_EQ(r.node_count(), 125);
  // Labels inherited: the volume of each label unchanged.
  double label1 = 0;
  for (int64_t t = 0; t < r.tet_count(); ++t) label1 += r.tet_labels[size_t(t)] == 1 ? refined_tet_volume(r, t) : 0;
  EXPECT_NEAR(label1, 500, 1e-9);
}

// Bey's refinement with the shortest diagonal keeps the shapes bounded: three refinements of the
// skewed tet lose little of its smallest dihedral angle, and the run repeats bit for bit.
TEST(TetMeshRefinement, RepeatedRefinementKeepsTheShapesAndIsDeterministic) {
  const TetMesh m = skewed_tet();
  const TetMesh r = ctsurg::refine_tet_mesh_uniformly(m, 3);
  EXPECT_EQ(r.tet_count(), 512);
  EXPECT_EQ(r.quality.inverted, 0);
  EXPECT_GT(r.quality.min_dihedral_deg, 0.5 * m.quality.min_dihedral_deg);
  EXPECT_LT(r.quality.max_radius_edge, 3 * m.quality.max_radius_edge);
  const TetMesh again = ctsurg::refine_tet_mesh_uniformly(ctsurg::refine_tet_mesh_uniformly(m, 1), 2);
  EXPECT_EQ(again.nodes, r.nodes);
  EXPECT_EQ(again.tets, r.tets);
  EXPECT_EQ(again.boundary_faces, r.boundary_faces);
  EXPECT_EQ(nlohmann::json::parse(r.criteria)["refinements"], 3);
  const TetMesh same = ctsurg::refine_tet_mesh_uniformly(m, 0);
  EXPECT_EQ(same.tets, m.tets);
}

TEST(TetMeshRefinement, RefusesABadMeshOrCount) {
  const TetMesh m = skewed_tet();
  EXPECT_THROW(ctsurg::refine_tet_mesh_uniformly(m, -1), ctsurg::InputError);
  TetMesh bad = m;
  bad.tets[3] = 7;  // out of range
  EXPECT_THROW(ctsurg::refine_tet_mesh_uniformly(bad), ctsurg::InputError);
}
