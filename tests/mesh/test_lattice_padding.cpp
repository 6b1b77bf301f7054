// Tests for mesh/include/ctsurg/mesh/lattice_padding.h: padded nodes keep their LPS positions and
// values on oblique and mirrored lattices, the frame has the given value, and marching cubes closes
// a surface that touched the border.
#include "ctsurg/mesh/lattice_padding.h"

#include "ctsurg/core/error.h"
#include "ctsurg/mesh/marching_cubes.h"
#include "surface_checks.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

namespace {

TEST(LatticePadding, NodesKeepTheirPositionsAndTheFrameHasTheValue) {
  ctsurg::ImageGeometry g;
  g.dims = {4, 3, 5};
  g.spacing = {0.7, 1.3, 2.0};
  g.origin = {10.0, -4.0, 2.5};
  g.direction = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix() *
                Eigen::Vector3d(1, -1, 1).asDiagonal();
  ctsurg::Volume<float> f(g);
  for (std::size_t n = 0; n < f.voxels.size(); ++n) f.voxels[n] = float(n) + 1.0f;
  for (const int64_t w : {1, 2}) {
    const auto p = ctsurg::pad_lattice(f, -7.0f, w);
    ASSERT_EQ(p.geometry.dims, (std::array<int64_t, 3>{4 + 2 * w, 3 + 2 * w, 5 + 2 * w}));
    int64_t frame = 0;
    for (int64_t k = 0; k < p.geometry.dims[2]; ++k)
      for (int64_t j = 0; j < p.geometry.dims[1]; ++j)
        for (int64_t i = 0; i < p.geometry.dims[0]; ++i) {
          const bool inner = i >= w && j >= w && k >= w && i < 4 + w && j < 3 + w && k < 5 + w;
          if (!inner) {
            EXPECT_EQ(p(i, j, k), -7.0f);
            ++frame;
            continue;
          }
          EXPECT_EQ(p(i, j, k), f(i - w, j - w, k - w));
          const Eigen::Vector3d a = p.geometry.index_to_world(Eigen::Vector3d(double(i), double(j), double(k)));
          const Eigen::Vector3d b = g.index_to_world(Eigen::Vector3d(double(i - w), double(j - w), double(k - w)));
          EXPECT_LT((a - b).norm(), 1e-9);
        }
    EXPECT_EQ(frame, p.geometry.voxel_count() - g.voxel_count());
  }
  EXPECT_THROW(ctsurg::pad_lattice(f, 0.0f, 0), ctsurg::InputError);
}

TEST(LatticePadding, ClosesASurfaceCutByTheBorder) {
  ctsurg::ImageGeometry g;
  g.dims = {6, 6, 6};
  ctsurg::Volume<float> f(g, 0.0f);
  for (int64_t k = 0; k < 4; ++k)  // a block touching the i = 0, j = 0 and k = 0 faces
    for (int64_t j = 0; j < 3; ++j)
      for (int64_t i = 0; i < 3; ++i) f(i, j, k) = 1.0f;
  ASSERT_TRUE(ctsurg::inside_touches_border(f, 0.5));
  EXPECT_NE(ctsurg::test::manifold_problem(ctsurg::marching_cubes(f, 0.5)), "");
  const auto padded = ctsurg::pad_lattice(f, 0.0f);
  EXPECT_FALSE(ctsurg::inside_touches_border(padded, 0.5));
  const auto m = ctsurg::marching_cubes(padded, 0.5);
  EXPECT_EQ(ctsurg::test::manifold_problem(m), "");
  // The closed surface runs half a node beyond the inside nodes: a 4 x 3 x 4 box of nodes.
  EXPECT_GT(ctsurg::test::enclosed_volume(m), 0.8 * 3.0 * 2.0 * 3.0);
  EXPECT_EQ(ctsurg::test::euler_characteristic(m), 2);
}

}  // namespace
