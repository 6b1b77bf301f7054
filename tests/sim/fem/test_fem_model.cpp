// Tests of sim/fem_model.h: precomputation, masses, the node CSR, mesh checks.
#include "ctsurg/sim/fem/fem_model.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/tet_mesh_file.h"
#include "ctsurg/sim/fem/fem_box_mesh.h"

#include <gtest/gtest.h>

#include <string>

namespace ctsurg::sim {
namespace {

const std::vector<double> kUnitTet{0, 0, 0, 2, 0, 0, 0, 3, 0, 0, 0, 4};

TEST(FemModel, SingleTetVolumeInverseAndMass) {
  FemMaterial mat;
  mat.density = 1e-3;
  const FemModel m = build_fem_model(kUnitTet, {0, 1, 2, 3}, mat);
  EXPECT_NEAR(m.rest_volume[0], 4.0, 1e-12);
  const double expected[9] = {0.5, 0, 0, 0, 1.0 / 3, 0, 0, 0, 0.25};
  for (int i = 0; i < 9; ++i) EXPECT_NEAR(m.dm_inverse[i], expected[i], 1e-15);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(m.node_mass[i], 1e-3, 1e-15);
  EXPECT_EQ(m.unused_nodes, 0);
}

TEST(FemModel, CsrListsEveryCornerOnceSortedByElement) {
  const auto box = fem_box_mesh({3, 3, 2}, {3, 3, 2});
  const FemModel m = build_fem_model(box.nodes, box.tets, FemMaterial{});
  std::vector<int> seen(m.tets.size(), 0);
  for (int32_t i = 0; i < m.node_count(); ++i)
    for (int32_t k = m.node_offsets[i]; k < m.node_offsets[i + 1]; ++k) {
      const int32_t c = m.node_corners[k];
      EXPECT_EQ(m.tets[c], i);
      ++seen[c];
      if (k > m.node_offsets[i]) {
        EXPECT_LT(m.node_corners[k - 1], c);
      }
    }
  for (int s : seen) EXPECT_EQ(s, 1);
  EXPECT_NEAR(fem_total_mass(m), 18 * FemMaterial{}.density, 1e-12);
}

TEST(FemModel, InvertedTetIsAnInputErrorNamingIt) {
  const auto box = fem_box_mesh({2, 1, 1}, {2, 1, 1});
  auto tets = box.tets;
  std::swap(tets[4 * 7 + 1], tets[4 * 7 + 2]);
  try {
    build_fem_model(box.nodes, tets, FemMaterial{});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "tets");
    EXPECT_NE(std::string(e.what()).find("tet 7 is inverted"), std::string::npos) << e.what();
  }
}

TEST(FemModel, DegenerateAndOutOfRangeTetsAreInputErrors) {
  std::vector<double> flat = kUnitTet;
  flat[11] = 1e-12;  // the fourth corner almost in the plane of the others
  EXPECT_THROW(build_fem_model(flat, {0, 1, 2, 3}, FemMaterial{}), InputError);
  EXPECT_THROW(build_fem_model(kUnitTet, {0, 1, 2, 4}, FemMaterial{}), InputError);
  EXPECT_THROW(build_fem_model(kUnitTet, {}, FemMaterial{}), InputError);
  FemMaterial bad;
  bad.poisson_ratio = 0.5;
  EXPECT_THROW(build_fem_model(kUnitTet, {0, 1, 2, 3}, bad), InputError);
}

TEST(FemModel, FromTetMeshAndUnusedNodes) {
  TetMesh mesh;
  mesh.nodes = kUnitTet;
  mesh.nodes.insert(mesh.nodes.end(), {9, 9, 9});
  mesh.tets = {0, 1, 2, 3};
  const FemModel m = build_fem_model(mesh, FemMaterial{});
  EXPECT_EQ(m.node_count(), 5);
  EXPECT_EQ(m.unused_nodes, 1);
  EXPECT_EQ(m.node_mass[4], 0);
}

}  // namespace
}  // namespace ctsurg::sim
