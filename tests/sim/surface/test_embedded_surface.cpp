// Tests for ctsurg/sim/surface/embedded_surface.h and surface_measures.h: a unit cube's surface
// encloses 1 mm^3 and has 6 mm^2; carried by a lattice model it follows the particles (a translation
// moves it rigidly, the volume stays), and a blade through it removes the crossed triangles; bad
// triangles are refused.
#include "ctsurg/sim/surface/embedded_surface.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/surface/surface_measures.h"
#include "ctsurg/sim/surface/tet_embedding.h"

#include <gtest/gtest.h>

namespace ctsurg::sim {
namespace {

// The cube [0, 1]^3 mm: 8 vertices, 12 outward triangles.
const std::vector<float> kCube{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1};
const std::vector<uint32_t> kFaces{0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                   2, 3, 7, 2, 7, 6, 1, 2, 6, 1, 6, 5, 0, 4, 7, 0, 7, 3};

TEST(SurfaceMeasures, UnitCube) {
  EXPECT_NEAR(enclosed_volume(kCube, kFaces), 1.0, 1e-12);
  EXPECT_NEAR(surface_area(kCube, kFaces), 6.0, 1e-12);
  std::vector<uint32_t> inward = kFaces;
  for (size_t f = 0; f < inward.size(); f += 3) std::swap(inward[f + 1], inward[f + 2]);
  EXPECT_NEAR(enclosed_volume(kCube, inward), -1.0, 1e-12);
}

// The cube's surface embedded in one tet that holds it, whose 4 nodes are the particles.
struct Embedded {
  std::vector<Real> rest;
  EmbeddedSurface surface;
};

Embedded embedded_cube() {
  TetMesh mesh;
  mesh.nodes = {-1, -1, -1, 5, -1, -1, -1, 5, -1, -1, -1, 5};
  mesh.tets = {0, 1, 2, 3};
  mesh.tet_labels = {1};
  return {std::vector<Real>(mesh.nodes.begin(), mesh.nodes.end()),
          EmbeddedSurface(embed_surface_in_tets(kCube, mesh, 1.0), kFaces)};
}

TEST(EmbeddedSurface, FollowsTheParticlesAndIsCutByTheBlade) {
  Embedded e = embedded_cube();
  EXPECT_FALSE(e.surface.empty());
  EXPECT_EQ(e.surface.vertex_count(), 8);
  ParticleState p(e.rest, std::vector<Real>(4, Real(1)));
  for (int32_t i = 0; i < 4; ++i) p.x[static_cast<size_t>(i)] += 2;  // translate by 2 mm in x
  std::vector<float> v;
  e.surface.move(p, e.rest, v, 1);
  ASSERT_EQ(v.size(), kCube.size());
  for (size_t i = 0; i < v.size(); ++i) EXPECT_NEAR(v[i], kCube[i] + (i % 3 == 0 ? 2 : 0), 1e-5);
  EXPECT_NEAR(enclosed_volume(v, e.surface.triangles()), 1.0, 1e-5);
  // A blade in the plane x = 2.5 crosses every triangle with vertices on both sides: the 8 of the four
  // faces around the x axis.
  const int64_t removed = e.surface.cut({{2.5, -10, -10}, {2.5, 10, -10}, {2.5, 0, 10}}, v, p);
  EXPECT_EQ(removed, 8);
  EXPECT_EQ(e.surface.triangles().size(), kFaces.size() - 24);
  EXPECT_TRUE(EmbeddedSurface().empty());
  EXPECT_THROW(EmbeddedSurface(embedded_cube().surface.coupling(), {0, 1, 8}), InputError);  // no vertex 8
}

}  // namespace
}  // namespace ctsurg::sim
