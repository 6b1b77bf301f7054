// Tests for ctsurg/sim/surface/tet_embedding.h: vertices inside a tet get its barycentric weights
// (non-negative, reproducing the vertex), vertices just outside take the nearest tet with clamped
// weights, far ones are refused; the embedded surface follows a rigid translation of the nodes and
// stays at rest for zero displacement.
#include "ctsurg/sim/surface/tet_embedding.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/base/particle_state.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace ctsurg;
using namespace ctsurg::sim;

namespace {

// A unit cube [0, 2]^3 mm split into 5 tets (a central one and four corners), positively oriented.
TetMesh cube_mesh() {
  TetMesh m;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) m.nodes.insert(m.nodes.end(), {2.0 * i, 2.0 * j, 2.0 * k});
  // Corners: 0 (0,0,0) 1 (2,0,0) 2 (0,2,0) 3 (2,2,0) 4 (0,0,2) 5 (2,0,2) 6 (0,2,2) 7 (2,2,2).
  m.tets = {0, 1, 2, 4, 3, 2, 1, 7, 5, 4, 7, 1, 6, 7, 4, 2, 1, 2, 4, 7};
  m.tet_labels.assign(5, 1);
  // Fix orientation where needed (positive volume).
  for (size_t t = 0; t < 5; ++t) {
    const auto p = [&](size_t a, int c) { return m.nodes[static_cast<size_t>(3 * m.tets[4 * t + a] + c)]; };
    double e[3][3];
    for (int a = 0; a < 3; ++a)
      for (int c = 0; c < 3; ++c) e[a][c] = p(static_cast<size_t>(a + 1), c) - p(0, c);
    const double det = e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) - e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                       e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
    if (det < 0) std::swap(m.tets[4 * t + 2], m.tets[4 * t + 3]);
  }
  return m;
}

}  // namespace

TEST(TetEmbedding, InsideVerticesGetBarycentricWeights) {
  const TetMesh mesh = cube_mesh();
  const std::vector<float> v = {0.3f, 0.4f, 0.5f, 1.0f, 1.0f, 1.0f, 1.9f, 1.7f, 0.2f, 0.0f, 0.0f, 0.0f};
  TetEmbeddingStats st;
  const SurfaceCoupling c = embed_surface_in_tets(v, mesh, 1.0, &st);
  EXPECT_EQ(st.inside, 4);
  EXPECT_EQ(st.outside, 0);
  for (int64_t i = 0; i < 4; ++i) {
    double sum = 0, p[3] = {0, 0, 0};
    for (int s = 0; s < 8; ++s) {
      const int32_t n = c.particles[static_cast<size_t>(8 * i + s)];
      if (s >= 4) {
        EXPECT_EQ(n, -1);
        continue;
      }
      const double w = c.weights[static_cast<size_t>(8 * i + s)];
      EXPECT_GE(w, -1e-6);
      sum += w;
      for (int k = 0; k < 3; ++k) p[k] += w * mesh.nodes[static_cast<size_t>(3 * n + k)];
    }
    EXPECT_NEAR(sum, 1.0, 1e-6);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(p[k], v[static_cast<size_t>(3 * i + k)], 1e-5);
  }
}

TEST(TetEmbedding, OutsideVerticesTakeTheNearestTetAndFarOnesAreRefused) {
  const TetMesh mesh = cube_mesh();
  TetEmbeddingStats st;
  const SurfaceCoupling c = embed_surface_in_tets({1.0f, 1.0f, 2.3f}, mesh, 1.0, &st);
  EXPECT_EQ(st.outside, 1);
  EXPECT_GT(st.max_outside_mm, 0);
  double sum = 0;
  for (int s = 0; s < 4; ++s) {
    EXPECT_GE(c.weights[static_cast<size_t>(s)], 0);
    sum += c.weights[static_cast<size_t>(s)];
  }
  EXPECT_NEAR(sum, 1.0, 1e-6);
  try {
    (void)embed_surface_in_tets({1.0f, 1.0f, 2.0f, 1.0f, 1.0f, 40.0f}, mesh, 1.0);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("vertex 1"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)embed_surface_in_tets({1.0f, 1.0f, 1.0f}, TetMesh{}), InputError);
}

TEST(TetEmbedding, EmbeddedSurfaceFollowsATranslationAndStaysAtRest) {
  const TetMesh mesh = cube_mesh();
  const std::vector<float> v = {0.3f, 0.4f, 0.5f, 1.0f, 1.0f, 2.2f, 1.9f, 1.7f, 0.2f};
  const SurfaceCoupling c = embed_surface_in_tets(v, mesh, 1.0);
  std::vector<Real> rest(mesh.nodes.begin(), mesh.nodes.end());
  ParticleState state(rest, std::vector<Real>(8, 1.0f));
  std::vector<float> out;
  move_surface(c, state, rest, out);
  EXPECT_EQ(out, v);
  for (int32_t i = 0; i < 8; ++i) {
    state.x[static_cast<size_t>(i)] += 3;
    state.z[static_cast<size_t>(i)] -= 1;
  }
  move_surface(c, state, rest, out);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_NEAR(out[3 * i], v[3 * i] + 3, 1e-5);
    EXPECT_NEAR(out[3 * i + 1], v[3 * i + 1], 1e-5);
    EXPECT_NEAR(out[3 * i + 2], v[3 * i + 2] - 1, 1e-5);
  }
}
