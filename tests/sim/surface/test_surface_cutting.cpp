// Tests for ctsurg/sim/surface/surface_cutting.h on the marching-cubes surface of a bar: a blade
// across the bar removes exactly the triangles with an edge crossing its plane, detaches every vertex
// from the particles across it, and then each half of the surface follows only its own half's
// particles (the incision opens); a blade beside the bar changes nothing.
#include "ctsurg/sim/surface/surface_cutting.h"

#include "block_surface.h"
#include "sim_test_models.h"

#include <gtest/gtest.h>

using namespace ctsurg;
using namespace ctsurg::sim;

namespace {

struct CutBar {
  SpringGridModel model;
  SurfaceMesh mesh;
  SurfaceCoupling coupling;
};

// 10 x 3 x 3 cells of 2 mm; cell centres x = 12 .. 30 mm.
CutBar cut_bar() {
  const auto occ = test::block_occupancy(10, 3, 3, 2.0);
  CutBar b{build_spring_grid_model(occ, test::test_material()), test::block_surface(occ), {}};
  b.coupling = couple_surface(b.mesh, b.model.lattice, b.model.cells);
  return b;
}

// A blade in the plane x = x0 covering the whole bar (y, z from -100 to 100 mm).
Triangle plane_blade(double x0, bool lower) {
  return lower ? Triangle{{x0, -100, -100}, {x0, 100, -100}, {x0, 100, 300}} : Triangle{{x0, -100, -100}, {x0, 100, 300}, {x0, -100, 300}};
}

}  // namespace

TEST(SurfaceCutting, BladeAcrossTheBarOpensTheSurface) {
  CutBar b = cut_bar();
  ParticleState state = b.model.make_state();
  std::vector<uint32_t> tri = b.mesh.triangles;
  const double x0 = 21.3;  // between the cell centres 20 and 22
  int64_t expected = 0;
  for (size_t f = 0; f < tri.size(); f += 3) {
    bool lo = false, hi = false;
    for (int e = 0; e < 3; ++e) (b.mesh.vertices[3 * tri[f + static_cast<size_t>(e)]] < x0 ? lo : hi) = true;
    expected += lo && hi;
  }
  ASSERT_GT(expected, 0);
  int64_t removed = 0, detached = 0;
  for (const bool lower : {true, false}) {
    const auto r = cut_surface(tri, b.coupling, b.mesh.vertices, state, plane_blade(x0, lower));
    removed += r.triangles_removed;
    detached += r.slots_detached;
  }
  EXPECT_EQ(removed, expected);
  EXPECT_EQ(static_cast<int64_t>(tri.size()), static_cast<int64_t>(b.mesh.triangles.size()) - 3 * expected);
  EXPECT_GT(detached, 0);
  // No vertex follows a particle on the other side.
  for (int64_t v = 0; v < b.coupling.vertex_count(); ++v) {
    const bool left = b.mesh.vertices[static_cast<size_t>(3 * v)] < x0;
    for (int s = 0; s < 8; ++s) {
      const int32_t p = b.coupling.particles[static_cast<size_t>(8 * v + s)];
      if (p >= 0) {
        EXPECT_EQ(b.model.rest_positions[static_cast<size_t>(3 * p)] < x0, left) << "vertex " << v;
      }
    }
  }
  // Move the right half's particles 4 mm further right: the right half of the surface goes with them
  // and the left half stays.
  for (int32_t i = 0; i < state.count(); ++i) {
    if (b.model.rest_positions[static_cast<size_t>(3 * i)] > x0) state.x[static_cast<size_t>(i)] += 4;
  }
  std::vector<float> moved;
  move_surface(b.coupling, state, b.model.rest_positions, moved);
  for (int64_t v = 0; v < b.coupling.vertex_count(); ++v) {
    const double dx = moved[static_cast<size_t>(3 * v)] - b.mesh.vertices[static_cast<size_t>(3 * v)];
    EXPECT_NEAR(dx, b.mesh.vertices[static_cast<size_t>(3 * v)] < x0 ? 0.0 : 4.0, 1e-5) << "vertex " << v;
  }
}

TEST(SurfaceCutting, BladeBesideTheBarChangesNothing) {
  CutBar b = cut_bar();
  const ParticleState state = b.model.make_state();
  std::vector<uint32_t> tri = b.mesh.triangles;
  const auto before = b.coupling.weights;
  const auto r = cut_surface(tri, b.coupling, b.mesh.vertices, state, plane_blade(50.0, true));
  EXPECT_EQ(r.triangles_removed, 0);
  EXPECT_EQ(r.slots_detached, 0);
  EXPECT_EQ(tri, b.mesh.triangles);
  EXPECT_EQ(b.coupling.weights, before);
}
