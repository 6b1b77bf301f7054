// Tests of sim/fem_model.h: precomputation, masses, the node CSR, mesh checks.
#include "ctsurg/sim/fem/fem_model.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/tet_mesh_file.h"
#include "ctsurg/sim/fem/fem_box_mesh.h"
#include "ctsurg/sim/fem/fem_forces.h"
#include "ctsurg/sim/fem/fem_static_solver.h"

#include <gtest/gtest.h>

#include <cmath>
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

namespace ctsurg::sim {
namespace {

// Two materials on one box, by element: the masses take each element's density, the materials are
// checked, and a model whose elements all point at one material is that material's model exactly.
TEST(FemModelMaterials, EachElementItsOwnMaterial) {
  const auto box = fem_box_mesh({4, 1, 1}, {4, 1, 1});
  FemMaterial soft, stiff;
  soft.law = FemLaw::linear, soft.youngs_modulus = 1e4, soft.density = 1e-3;
  stiff.law = FemLaw::neo_hookean, stiff.youngs_modulus = 4e4, stiff.density = 2e-3;
  const int32_t tets = static_cast<int32_t>(box.tets.size() / 4);
  std::vector<int32_t> half(static_cast<size_t>(tets));
  for (int32_t e = 0; e < tets; ++e) half[static_cast<size_t>(e)] = e < tets / 2 ? 0 : 1;  // cells are 6 tets each, in x order
  const FemModel m = build_fem_model(box.nodes, box.tets, {soft, stiff}, half);
  EXPECT_EQ(m.material_of(0).law, FemLaw::linear);
  EXPECT_EQ(m.material_of(tets - 1).law, FemLaw::neo_hookean);
  EXPECT_FALSE(m.every_law(FemLaw::linear));
  EXPECT_TRUE(m.any_indefinite_tangent());
  EXPECT_NEAR(fem_total_mass(m), 2 * 1e-3 + 2 * 2e-3, 1e-15);  // 2 mm^3 of each
  EXPECT_NEAR(m.lame_of(tets - 1).mu, 4e4 / (2 * 1.45), 1e-9);
  // All on material 1: the stiff model, bit for bit.
  const FemModel all_stiff = build_fem_model(box.nodes, box.tets, {soft, stiff}, std::vector<int32_t>(static_cast<size_t>(tets), 1));
  const FemModel stiff_only = build_fem_model(box.nodes, box.tets, stiff);
  std::vector<double> u(box.nodes.size());
  for (size_t i = 0; i < u.size(); ++i) u[i] = 0.01 * std::sin(1.7 * static_cast<double>(i));
  std::vector<double> fa, fb;
  fem_internal_forces(all_stiff, u, fa);
  fem_internal_forces(stiff_only, u, fb);
  EXPECT_EQ(fa, fb);
  EXPECT_EQ(all_stiff.node_mass, stiff_only.node_mass);
  // The checks name the field.
  const auto field_of = [&](const std::vector<FemMaterial>& materials, const std::vector<int32_t>& ids) {
    try {
      (void)build_fem_model(box.nodes, box.tets, materials, ids);
    } catch (const InputError& e) {
      return e.field();
    }
    return std::string("accepted");
  };
  EXPECT_EQ(field_of({soft, stiff}, {0, 1}), "materials");  // not one id per tet
  std::vector<int32_t> bad = half;
  bad[3] = 2;
  EXPECT_EQ(field_of({soft, stiff}, bad), "materials");
  EXPECT_EQ(field_of(std::vector<FemMaterial>(17, soft), {}), "materials");
  FemMaterial broken = stiff;
  broken.poisson_ratio = 0.5;
  EXPECT_EQ(field_of({soft, broken}, half), "poisson_ratio");
  // The linear copy keeps each material's stiffness and density.
  const FemModel lin = fem_linearised(m);
  EXPECT_TRUE(lin.every_law(FemLaw::linear));
  EXPECT_EQ(lin.lame_of(tets - 1).mu, m.lame_of(tets - 1).mu);
}

// Two materials in series: a bar whose left half has E_a and right half E_b (linear law, nu = 0),
// fixed at x = 0 and stretched by d at x = 8: uniform stress, so the interface at x = 4 moves
// d (1/E_a) / (1/E_a + 1/E_b) (exact for linear tets: the kink lies on a mesh plane).
TEST(FemModelMaterials, TwoMaterialsInSeriesShareTheStretchByCompliance) {
  const auto box = fem_box_mesh({8, 2, 2}, {8, 2, 2});
  FemMaterial a, b;
  a.law = b.law = FemLaw::linear;
  a.poisson_ratio = b.poisson_ratio = 0;
  a.youngs_modulus = 1e4, b.youngs_modulus = 3e4;
  std::vector<int32_t> ids;
  for (size_t e = 0; e < box.tets.size() / 4; ++e) {
    double cx = 0;
    for (int k = 0; k < 4; ++k) cx += 0.25 * box.nodes[3 * static_cast<size_t>(box.tets[4 * e + k])];
    ids.push_back(cx < 4 ? 0 : 1);
  }
  const FemModel m = build_fem_model(box.nodes, box.tets, {a, b}, ids);
  FemBoundaryConditions bc;
  const double d = 0.8;
  for (int32_t i = 0; i < m.node_count(); ++i) {
    const double x = m.nodes[3 * static_cast<size_t>(i)];
    if (x < 1e-9) bc.fixed_nodes.push_back(i);
    if (x > 8 - 1e-9) {
      bc.prescribed_nodes.push_back(i);
      for (const double v : {d, 0.0, 0.0}) bc.prescribed_displacements.push_back(v);
    }
  }
  const FemStaticResult r = solve_fem_static(m, bc, FemLoads{});
  ASSERT_TRUE(r.report.converged);
  const double expected = d * (1 / a.youngs_modulus) / (1 / a.youngs_modulus + 1 / b.youngs_modulus);
  for (int32_t i = 0; i < m.node_count(); ++i) {
    if (std::abs(m.nodes[3 * static_cast<size_t>(i)] - 4) > 1e-9) continue;
    EXPECT_NEAR(r.displacements[3 * static_cast<size_t>(i)], expected, 1e-9);
    EXPECT_NEAR(r.displacements[3 * static_cast<size_t>(i) + 1], 0, 1e-9);
  }
}

}  // namespace
}  // namespace ctsurg::sim
