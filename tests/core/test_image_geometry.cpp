#include "ctsurg/core/image_geometry.h"

#include "ctsurg/core/error.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

using namespace ctsurg;

TEST(ImageGeometry, IndexWorldRoundTripOnObliqueAndShearedLattices) {
  ImageGeometry g;
  g.dims = {10, 20, 30};
  g.spacing = {0.5, 0.7, 2.0};
  g.origin = {-100, 20, 300};
  g.direction = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Vector3d ijk(3.25, 7.5, 11);
  EXPECT_NEAR((g.world_to_index(g.index_to_world(ijk)) - ijk).norm(), 0.0, 1e-10);
  EXPECT_NEAR(g.voxel_volume_mm3(), 0.5 * 0.7 * 2.0, 1e-12);
  EXPECT_TRUE(g.is_orthonormal());
  // Gantry-tilt shear: slice axis tilted 20 degrees, voxel volume shrinks by cos(20).
  ImageGeometry s = g;
  s.direction = Eigen::Matrix3d::Identity();
  s.direction.col(2) = Eigen::Vector3d(0, std::sin(0.349066), std::cos(0.349066));
  EXPECT_FALSE(s.is_orthonormal());
  EXPECT_NEAR(s.voxel_volume_mm3(), 0.7 * std::cos(0.349066), 1e-6);
  EXPECT_NEAR((s.world_to_index(s.index_to_world(ijk)) - ijk).norm(), 0.0, 1e-10);
  EXPECT_TRUE(g.same_lattice(g));
  EXPECT_FALSE(g.same_lattice(s));
}

TEST(ImageGeometry, ValidateRejectsAbsurdGeometryWithTheField) {
  ImageGeometry g;
  g.dims = {2, 2, 2};
  EXPECT_NO_THROW(g.validate("f"));
  auto bad = g;
  bad.spacing[1] = 0;
  try {
    bad.validate("f.nii");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "spacing");
  }
  bad = g;
  bad.spacing[0] = -1;
  EXPECT_THROW(bad.validate("f"), InputError);
  bad = g;
  bad.dims[2] = 0;
  EXPECT_THROW(bad.validate("f"), InputError);
  bad = g;
  bad.direction.col(1) = bad.direction.col(0);
  EXPECT_THROW(bad.validate("f"), InputError);
  bad = g;
  bad.origin[0] = std::nan("");
  EXPECT_THROW(bad.validate("f"), InputError);
}

// Issue 17: a MetaImage DimSize of 2^32 overflowed voxel_count() and an srow of -1.7e38 hung a later
// stage. Geometry that is finite but not sane is refused by validate().
TEST(ImageGeometry, InsaneGeometryIsRefused) {
  ImageGeometry g;
  g.dims = {4, 4, 4};
  EXPECT_NO_THROW(g.validate("f"));
  const auto refused = [](const ImageGeometry& bad, const std::string& field) {
    try {
      bad.validate("f");
      ADD_FAILURE() << "accepted; expected a refusal naming " << field;
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), field) << e.what();
    }
  };
  ImageGeometry b = g;
  b.dims = {int64_t{1} << 32, int64_t{1} << 32, 4};
  b.spacing = Eigen::Vector3d(1e-3, 1e-3, 1.0);  // 4.3 km each way: only the count is wrong
  refused(b, "dims");
  b = g;
  b.spacing[1] = 1.7e38;
  refused(b, "spacing");
  b.spacing[1] = 1e-9;
  refused(b, "spacing");
  b = g;
  b.origin[2] = -1.7e38;
  refused(b, "origin");
  b = g;
  b.spacing[0] = 9000;
  b.dims[0] = 2000;  // 18 km long
  refused(b, "origin");
}
