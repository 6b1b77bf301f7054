// Tests for mesh/include/ctsurg/mesh/tet_mesh_quality.h: known values on the regular and the
// right-corner tet, invariance under rotation, scaling and vertex order, sliver and inverted tet
// detection, degenerate tets without NaN, and the report's histogram.
#include "ctsurg/mesh/tet_mesh_quality.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <random>

namespace {

using Eigen::Vector3d;

const double kRegularDihedral = std::acos(1.0 / 3.0) * 180.0 / std::numbers::pi;  // 70.5288 deg

std::array<Vector3d, 4> regular_tet() {
  return {Vector3d(1, 1, 1), Vector3d(1, -1, -1), Vector3d(-1, -1, 1), Vector3d(-1, 1, -1)};
}

TEST(TetMeshQuality, RegularTetKnownValues) {
  const auto p = regular_tet();
  ASSERT_GT(ctsurg::tet_signed_volume(p[0], p[1], p[2], p[3]), 0.0);
  EXPECT_NEAR(ctsurg::tet_signed_volume(p[0], p[1], p[2], p[3]), 8.0 / 3.0, 1e-12);  // cube 8 minus 4 corners of 4/3
  for (const double a : ctsurg::tet_dihedral_angles_deg(p[0], p[1], p[2], p[3])) EXPECT_NEAR(a, kRegularDihedral, 1e-9);
  EXPECT_NEAR(kRegularDihedral, 70.5288, 1e-4);
  EXPECT_NEAR(ctsurg::tet_radius_edge_ratio(p[0], p[1], p[2], p[3]), std::sqrt(6.0) / 4.0, 1e-12);
}

TEST(TetMeshQuality, RightCornerTetKnownValues) {
  const Vector3d o(0, 0, 0), x(1, 0, 0), y(0, 1, 0), z(0, 0, 1);
  const auto a = ctsurg::tet_dihedral_angles_deg(o, x, y, z);
  // Edges at the corner (01, 02, 03): 90 deg; the others: acos(1/sqrt(3)) = 54.7356 deg.
  const double slanted = std::acos(1.0 / std::sqrt(3.0)) * 180.0 / std::numbers::pi;
  EXPECT_NEAR(a[0], 90.0, 1e-9);
  EXPECT_NEAR(a[1], 90.0, 1e-9);
  EXPECT_NEAR(a[2], 90.0, 1e-9);
  EXPECT_NEAR(a[3], slanted, 1e-9);
  EXPECT_NEAR(a[4], slanted, 1e-9);
  EXPECT_NEAR(a[5], slanted, 1e-9);
  // Circumcentre (1/2, 1/2, 1/2): R = sqrt(3)/2, shortest edge 1.
  EXPECT_NEAR(ctsurg::tet_radius_edge_ratio(o, x, y, z), std::sqrt(3.0) / 2.0, 1e-12);
  EXPECT_NEAR(ctsurg::tet_signed_volume(o, x, y, z), 1.0 / 6.0, 1e-15);
  EXPECT_NEAR(ctsurg::tet_signed_volume(o, y, x, z), -1.0 / 6.0, 1e-15);
}

TEST(TetMeshQuality, InvariantUnderRotationScaleAndVertexOrder) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 50; ++trial) {
    std::array<Vector3d, 4> p;
    for (auto& v : p) v = Vector3d(u(rng), u(rng), u(rng));
    const auto a = ctsurg::tet_dihedral_angles_deg(p[0], p[1], p[2], p[3]);
    const double re = ctsurg::tet_radius_edge_ratio(p[0], p[1], p[2], p[3]);
    const Eigen::Matrix3d r = Eigen::AngleAxisd(u(rng) * 3.0, Vector3d(u(rng), u(rng), 1.0).normalized()).toRotationMatrix();
    const double s = 0.1 + 10.0 * std::abs(u(rng));
    const Vector3d shift(u(rng) * 100.0, u(rng) * 100.0, u(rng) * 100.0);
    std::array<Vector3d, 4> q;
    for (std::size_t i = 0; i < 4; ++i) q[i] = s * (r * p[i]) + shift;
    // Reordered: (1, 0, 3, 2) keeps the orientation and swaps edge pairs 01<->01, 02<->13, 03<->12, 23<->23.
    const auto b = ctsurg::tet_dihedral_angles_deg(q[1], q[0], q[3], q[2]);
    EXPECT_NEAR(a[0], b[0], 1e-6);
    EXPECT_NEAR(a[1], b[4], 1e-6);
    EXPECT_NEAR(a[2], b[3], 1e-6);
    EXPECT_NEAR(a[5], b[5], 1e-6);
    EXPECT_NEAR(re, ctsurg::tet_radius_edge_ratio(q[1], q[0], q[3], q[2]), 1e-6 * re);
    EXPECT_NEAR(ctsurg::tet_signed_volume(q[1], q[0], q[3], q[2]), s * s * s * ctsurg::tet_signed_volume(p[0], p[1], p[2], p[3]),
                1e-9 * s * s * s);
  }
}

TEST(TetMeshQuality, FlatSliverIsDetectedThoughItsRadiusEdgeIsGood) {
  // Four points near a square's corners, two lifted by h: a sliver with a good radius-edge ratio.
  const double h = 0.05;
  const Vector3d a(1, 0, 0), b(-1, 0, 0), c(0, 1, h), d(0, -1, h);
  const std::array<Vector3d, 4> p = ctsurg::tet_signed_volume(a, b, c, d) > 0 ? std::array<Vector3d, 4>{a, b, c, d}
                                                                              : std::array<Vector3d, 4>{b, a, c, d};
  const auto ang = ctsurg::tet_dihedral_angles_deg(p[0], p[1], p[2], p[3]);
  EXPECT_LT(*std::min_element(ang.begin(), ang.end()), 10.0);
  EXPECT_GT(*std::max_element(ang.begin(), ang.end()), 170.0);
  EXPECT_LT(ctsurg::tet_radius_edge_ratio(p[0], p[1], p[2], p[3]), 1.0);

  const auto r = regular_tet();
  std::vector<double> nodes;
  for (const auto& v : r) nodes.insert(nodes.end(), {v[0], v[1], v[2]});
  for (const auto& v : p) nodes.insert(nodes.end(), {v[0] + 5.0, v[1], v[2]});
  const std::vector<int32_t> tets{0, 1, 2, 3, 4, 5, 6, 7};
  const auto q = ctsurg::tet_mesh_quality(nodes, tets);
  EXPECT_EQ(q.slivers, 1);
  EXPECT_EQ(q.inverted, 0);
  EXPECT_LT(q.min_dihedral_deg, 10.0);
  EXPECT_GT(q.max_dihedral_deg, 170.0);
  EXPECT_NEAR(q.volume_mm3, 8.0 / 3.0 + ctsurg::tet_signed_volume(p[0], p[1], p[2], p[3]), 1e-12);
  // A higher threshold than the sliver's angle but lower than the regular tet's still counts one.
  EXPECT_EQ(ctsurg::tet_mesh_quality(nodes, tets, 60.0).slivers, 1);
  EXPECT_EQ(ctsurg::tet_mesh_quality(nodes, tets, 75.0).slivers, 2);
}

TEST(TetMeshQuality, ReportCountsInvertedTetsAndFillsTheHistogram) {
  const auto r = regular_tet();
  std::vector<double> nodes;
  for (const auto& v : r) nodes.insert(nodes.end(), {v[0], v[1], v[2]});
  nodes.insert(nodes.end(), {0.0, 0.0, 0.0});
  // The regular tet, the same inverted, and a thin needle-ish tet with a large radius-edge ratio.
  nodes.insert(nodes.end(), {0.0, 0.0, 0.0, 10.0, 0.0, 0.0, 0.0, 10.0, 0.0, 0.0, 0.0, 0.05});
  const std::vector<int32_t> tets{0, 1, 2, 3, 1, 0, 2, 3, 5, 6, 7, 8};
  const auto q = ctsurg::tet_mesh_quality(nodes, tets);
  EXPECT_EQ(q.inverted, 1);
  ASSERT_EQ(q.radius_edge_bin_edges.size(), q.radius_edge_histogram.size() + 1);
  EXPECT_EQ(std::accumulate(q.radius_edge_histogram.begin(), q.radius_edge_histogram.end(), int64_t{0}), 3);
  EXPECT_EQ(q.radius_edge_histogram.front(), 2);  // both regular tets in [0.6, 0.7)
  EXPECT_EQ(q.radius_edge_histogram.back(), 1);   // the flat corner tet: R ~ 7.07 / 0.05, in [2.0, inf)
  EXPECT_NEAR(q.min_radius_edge, std::sqrt(6.0) / 4.0, 1e-12);
  EXPECT_GT(q.max_radius_edge, 100.0);
  EXPECT_NEAR(q.volume_mm3, 10.0 * 10.0 * 0.05 / 6.0, 1e-9);  // the regular pair cancels
}

TEST(TetMeshQuality, DegenerateTetGivesNoNaN) {
  const Vector3d a(0, 0, 0), b(1, 0, 0), c(2, 0, 0), d(0, 1, 0);  // three collinear points, all coplanar
  for (const double x : ctsurg::tet_dihedral_angles_deg(a, b, c, d)) EXPECT_FALSE(std::isnan(x));
  EXPECT_TRUE(std::isinf(ctsurg::tet_radius_edge_ratio(a, b, c, d)));
  EXPECT_EQ(ctsurg::tet_signed_volume(a, b, c, d), 0.0);
  const auto q = ctsurg::tet_mesh_quality({0, 0, 0, 1, 0, 0, 2, 0, 0, 0, 1, 0}, {0, 1, 2, 3});
  EXPECT_EQ(q.inverted, 1);
  EXPECT_EQ(q.slivers, 1);
}

}  // namespace
