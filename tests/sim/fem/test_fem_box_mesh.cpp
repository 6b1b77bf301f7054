// Tests of sim/fem_box_mesh.h.
#include "ctsurg/sim/fem/fem_box_mesh.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/fem/fem_model.h"

#include <gtest/gtest.h>

#include <map>
#include <set>

namespace ctsurg::sim {
namespace {

TEST(FemBoxMesh, CountsVolumeOrientationAndConformity) {
  const auto m = fem_box_mesh({3, 2, 4}, {3.0, 1.0, 2.0}, {1, 2, 3});
  EXPECT_EQ(m.nodes.size(), 3u * 4 * 3 * 5);
  EXPECT_EQ(m.tets.size(), 4u * 6 * 3 * 2 * 4);
  const FemModel model = build_fem_model(m.nodes, m.tets, FemMaterial{});  // throws on an inverted tet
  EXPECT_NEAR(fem_total_volume(model), 6.0, 1e-12);
  // Conforming: every interior face is shared by exactly two tets, boundary faces by one; the
  // boundary area equals the box's.
  std::map<std::set<int32_t>, int> faces;
  for (std::size_t e = 0; e < m.tets.size() / 4; ++e)
    for (int skip = 0; skip < 4; ++skip) {
      std::set<int32_t> f;
      for (int a = 0; a < 4; ++a)
        if (a != skip) f.insert(m.tets[4 * e + a]);
      ++faces[f];
    }
  int boundary = 0;
  for (const auto& [f, n] : faces) {
    EXPECT_LE(n, 2);
    boundary += n == 1;
  }
  EXPECT_EQ(boundary, 2 * 2 * (3 * 2 + 2 * 4 + 3 * 4));
}

TEST(FemBoxMesh, RejectsBadArguments) {
  EXPECT_THROW(fem_box_mesh({0, 1, 1}, {1, 1, 1}), InputError);
  EXPECT_THROW(fem_box_mesh({1, 1, 1}, {1, -1, 1}), InputError);
}

}  // namespace
}  // namespace ctsurg::sim
