// Tests for mesh/include/ctsurg/mesh/lattice_tie.h: after the vertices move, the recomputed weights
// reproduce every vertex, sum to 1, and the nearest inside node is the brute-force nearest one.
#include "ctsurg/mesh/lattice_tie.h"

#include "ctsurg/core/error.h"
#include "ctsurg/mesh/marching_cubes.h"
#include "ctsurg/preprocess/synthetic_phantom.h"
#include "surface_checks.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <limits>
#include <random>

namespace {

ctsurg::Volume<float> torus_ct(const Eigen::Matrix3d& direction) {
  ctsurg::PhantomShape s;
  s.kind = ctsurg::PhantomKind::Torus;
  s.major_mm = 12.0;
  s.minor_mm = 4.0;
  ctsurg::PhantomRasterOptions o;
  o.spacing_mm = {1.1, 0.9, 1.4};
  o.supersample = 2;
  auto hu = ctsurg::rasterise_phantom(s, o, "test").hu;
  hu.geometry.direction = direction;  // the same samples on a rotated, mirrored lattice
  return hu;
}

TEST(LatticeTie, WeightsReproduceMovedVerticesAndNearestNodeIsNearest) {
  const Eigen::Matrix3d dir =
      Eigen::AngleAxisd(0.5, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix() * Eigen::Vector3d(1, 1, -1).asDiagonal();
  const auto f = torus_ct(dir);
  const double iso = -470.0;
  auto m = ctsurg::marching_cubes(f, iso);
  ASSERT_GT(m.vertex_count(), 500);
  std::mt19937 rng(7);
  std::normal_distribution<float> jitter(0.0f, 0.4f);
  for (float& x : m.vertices) x += jitter(rng);
  ctsurg::tie_surface_to_lattice(m, f);
  const auto& g = f.geometry;
  for (int64_t v = 0; v < m.vertex_count(); ++v) {
    const auto i = static_cast<std::size_t>(v);
    const Eigen::Vector3d x = ctsurg::test::vertex(m, static_cast<uint32_t>(v));
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    double sum = 0.0;
    for (int c = 0; c < 8; ++c) {
      const double w = m.grid_weights[8 * i + static_cast<std::size_t>(c)];
      sum += w;
      p += w * g.index_to_world(Eigen::Vector3d(m.grid_cell[3 * i] + (c & 1), m.grid_cell[3 * i + 1] + ((c >> 1) & 1),
                                                m.grid_cell[3 * i + 2] + ((c >> 2) & 1)));
    }
    ASSERT_NEAR(sum, 1.0, 1e-5);
    ASSERT_LT((p - x).norm(), 1e-3) << "vertex " << v;
    // Brute force over the whole lattice.
    double best = std::numeric_limits<double>::infinity();
    for (int64_t k = 0; k < g.dims[2]; ++k)
      for (int64_t j = 0; j < g.dims[1]; ++j)
        for (int64_t n = 0; n < g.dims[0]; ++n)
          if (f(n, j, k) >= iso) best = std::min(best, (g.index_to_world(Eigen::Vector3d(double(n), double(j), double(k))) - x).norm());
    const Eigen::Vector3d node(m.nearest_node[3 * i], m.nearest_node[3 * i + 1], m.nearest_node[3 * i + 2]);
    ASSERT_GE(f(m.nearest_node[3 * i], m.nearest_node[3 * i + 1], m.nearest_node[3 * i + 2]), iso);
    ASSERT_NEAR((g.index_to_world(node) - x).norm(), best, 1e-6) << "vertex " << v;
    if (v > 300) break;  // the brute force is O(lattice); 300 vertices make the point
  }
}

TEST(LatticeTie, RefusesAnotherLattice) {
  const auto f = torus_ct(Eigen::Matrix3d::Identity());
  auto m = ctsurg::marching_cubes(f, -470.0);
  auto other = f;
  other.geometry.origin.x() += 5.0;
  EXPECT_THROW(ctsurg::tie_surface_to_lattice(m, other), ctsurg::InputError);
}

}  // namespace
