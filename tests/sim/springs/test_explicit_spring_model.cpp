#include "ctsurg/sim/springs/explicit_spring_model.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/tet_mesh_file.h"
#include "sim_test_models.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace ctsurg::sim {
namespace {

TEST(ExplicitSpringModel, CsrRowsHoldEachSpringOnBothEndsInOrder) {
  const std::vector<Real> rest{0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  const auto m = build_explicit_spring_model(rest, {1, 2, 3, 4}, {{3, 0, 10, 1, 0}, {1, 0, 20, 1, 0}, {2, 1, 30, 1.5, 0.1}});
  ASSERT_EQ(m.row_offsets, (std::vector<int32_t>{0, 2, 4, 5, 6}));
  EXPECT_EQ(std::vector<int32_t>(m.row_neighbour.begin(), m.row_neighbour.begin() + 2), (std::vector<int32_t>{1, 3}));
  EXPECT_EQ(std::vector<int32_t>(m.row_spring.begin(), m.row_spring.begin() + 2), (std::vector<int32_t>{1, 0}));
  for (int32_t p = 0; p < m.particle_count(); ++p)
    for (int32_t e = m.row_offsets[p]; e < m.row_offsets[p + 1]; ++e) {
      const int32_t s = m.row_spring[e], q = m.row_neighbour[e];
      EXPECT_TRUE((m.spring_ends[2 * s] == p && m.spring_ends[2 * s + 1] == q) ||
                  (m.spring_ends[2 * s] == q && m.spring_ends[2 * s + 1] == p));
    }
  auto cut = m;
  EXPECT_TRUE(cut_explicit_spring(cut, 1));
  EXPECT_FALSE(cut_explicit_spring(cut, 1));
  EXPECT_EQ(cut.alive_spring_count(), 2);
  EXPECT_THROW(build_explicit_spring_model(rest, {1, 2, 3, 4}, {{0, 0, 1, 1, 0}}), InputError);
  EXPECT_THROW(build_explicit_spring_model(rest, {1, 2, 3, 4}, {{0, 4, 1, 1, 0}}), InputError);
  EXPECT_THROW(build_explicit_spring_model(rest, {1, 2, 3, 4}, {{0, 1, -1, 1, 0}}), InputError);
  EXPECT_THROW(build_explicit_spring_model(rest, {1, 0, 3, 4}, {}), InputError);
}

TEST(ExplicitSpringModel, FromTetMeshEdgesWithLumpedMasses) {
  TetMesh mesh;  // two tets sharing the face (1, 2, 3): 5 nodes, 9 edges
  mesh.nodes = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
  mesh.tets = {0, 1, 2, 3, 4, 1, 3, 2};
  const auto m = explicit_model_from_tet_mesh(mesh, 2.0, 100.0);
  EXPECT_EQ(m.particle_count(), 5);
  EXPECT_EQ(m.spring_count(), 9);
  double total = 0;
  for (Real v : m.mass) total += v;
  EXPECT_NEAR(total, 2.0 * (1.0 / 6 + 1.0 / 3), 1e-6);  // volumes 1/6 and 1/3
  EXPECT_NEAR(m.mass[0], 2.0 * (1.0 / 6) / 4, 1e-6);
  for (int32_t s = 0; s < m.spring_count(); ++s) {
    const int32_t a = m.spring_ends[2 * s], b = m.spring_ends[2 * s + 1];
    double d2 = 0;
    for (int k = 0; k < 3; ++k) d2 += std::pow(mesh.nodes[3 * a + k] - mesh.nodes[3 * b + k], 2);
    EXPECT_NEAR(m.rest_length[s], std::sqrt(d2), 1e-6);
  }
  TetMesh loose = mesh;
  loose.nodes.insert(loose.nodes.end(), {5, 5, 5});  // a node no tet uses
  EXPECT_THROW(explicit_model_from_tet_mesh(loose, 2.0, 100.0), InputError);
}

TEST(ExplicitSpringModel, FromGridHasTheGridsSprings) {
  auto grid = build_spring_grid_model(test::block_occupancy(3, 2, 2, 1.5), test::test_material(100, 50, 0.5));
  cut_grid_spring(grid, 0, 0);
  const auto m = explicit_model_from_grid(grid);
  EXPECT_EQ(m.spring_count(), grid.spring_count());
  EXPECT_EQ(m.rest_positions, grid.rest_positions);
  for (int32_t s = 0; s < m.spring_count(); ++s) {
    EXPECT_LT(m.spring_ends[2 * s], m.spring_ends[2 * s + 1]);
    EXPECT_TRUE(m.rest_length[s] == grid.rest_length[0] || m.rest_length[s] == grid.rest_length[6]);
    EXPECT_EQ(m.stiffness[s], m.rest_length[s] == grid.rest_length[0] ? 100 : 50);
  }
}

}  // namespace
}  // namespace ctsurg::sim
