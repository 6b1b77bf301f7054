#include "ctsurg/sim/surface/surface_coupling.h"

#include "ctsurg/core/error.h"
#include "ctsurg/mesh/lattice_padding.h"
#include "ctsurg/mesh/marching_cubes.h"
#include "sim_test_models.h"

#include <gtest/gtest.h>

namespace ctsurg::sim {
namespace {

using test::block_occupancy;
using test::test_material;

// The block's occupancy as a field (1 inside, 0 outside) and its marching-cubes surface at 0.5, as
// ctsurg-surface makes it from /grid/fraction.
struct BlockSurface {
  SpringGridModel model;
  SurfaceMesh mesh;
};

BlockSurface block_surface(bool padded) {
  const auto occ = block_occupancy(4, 3, 5, 2.0);
  Volume<float> field(occ.geometry, 0.f);
  for (std::size_t i = 0; i < occ.voxels.size(); ++i) field.voxels[i] = occ.voxels[i] ? 1.f : 0.f;
  if (padded) field = pad_lattice(field, 0.f, 2);
  return {build_spring_grid_model(occ, test_material()), marching_cubes(field, 0.5)};
}

TEST(SurfaceCoupling, RestIsReproducedExactlyAndRigidTranslationFollowed) {
  for (bool padded : {false, true})
    for (CouplingMode mode : {CouplingMode::trilinear, CouplingMode::nearest_particle}) {
      const auto [model, mesh] = block_surface(padded);
      ASSERT_GT(mesh.vertex_count(), 50);
      const auto coupling = couple_surface(mesh, model.lattice, model.cells, mode);
      auto state = model.make_state();
      std::vector<float> v;
      move_surface(coupling, state, model.rest_positions, v);
      ASSERT_EQ(v.size(), mesh.vertices.size());
      for (std::size_t i = 0; i < v.size(); ++i) ASSERT_EQ(v[i], mesh.vertices[i]) << "coordinate " << i;
      const Real t[3] = {0.5f, -0.25f, 1.0f};  // exact in float at these positions
      for (int32_t p = 0; p < state.count(); ++p) state.x[p] += t[0], state.y[p] += t[1], state.z[p] += t[2];
      move_surface(coupling, state, model.rest_positions, v);
      // Renormalised weights sum to 1 up to float rounding: the translation is followed to ~1 ulp.
      for (std::size_t i = 0; i < v.size(); ++i) ASSERT_NEAR(v[i], mesh.vertices[i] + t[i % 3], 1e-5) << "coordinate " << i;
    }
}

TEST(SurfaceCoupling, VerticesFollowTheParticlesOfTheirCell) {
  const auto [model, mesh] = block_surface(false);
  const auto coupling = couple_surface(mesh, model.lattice, model.cells);
  auto state = model.make_state();
  const int32_t moved = model.particle_at(1, 1, 1);  // a corner particle of the block
  state.z[moved] -= 1.0f;
  std::vector<float> v;
  move_surface(coupling, state, model.rest_positions, v);
  int followers = 0;
  for (int64_t i = 0; i < mesh.vertex_count(); ++i) {
    double w = 0;
    for (int c = 0; c < 8; ++c)
      if (coupling.particles[8 * i + c] == moved) w += coupling.weights[8 * i + c];
    EXPECT_NEAR(v[3 * i + 2], mesh.vertices[3 * i + 2] - w, 1e-5);
    EXPECT_EQ(v[3 * i], mesh.vertices[3 * i]);
    followers += w > 0;
  }
  EXPECT_GE(followers, 3);  // the corner's three faces have vertices next to it
}

TEST(SurfaceCoupling, RefusesASurfaceFromAnotherLattice) {
  auto [model, mesh] = block_surface(false);
  mesh.lattice.origin += Eigen::Vector3d(0.7, 0, 0);  // not on a node
  EXPECT_THROW(couple_surface(mesh, model.lattice, model.cells), InputError);
  auto [model2, mesh2] = block_surface(false);
  mesh2.lattice.spacing *= 1.5;
  EXPECT_THROW(couple_surface(mesh2, model2.lattice, model2.cells), InputError);
  auto [model3, mesh3] = block_surface(false);
  mesh3.grid_weights.clear();
  EXPECT_THROW(couple_surface(mesh3, model3.lattice, model3.cells), InputError);
}

}  // namespace
}  // namespace ctsurg::sim
