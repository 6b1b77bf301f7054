#include "ctsurg/core/volume_hdf5.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/memory_guard.h"
#include "ctsurg/core/xdmf_sidecar.h"
#include "test_support.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

using namespace ctsurg;

TEST(VolumeHdf5, GeometryAndValuesRoundTripExactly) {
  test::TempDir tmp;
  ImageGeometry g;
  g.dims = {7, 5, 3};
  g.spacing = {0.4883, 0.4883, 4.0019};
  g.origin = {-125.0, -123.5404569, 5.8360586};
  g.direction = Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  Volume<float> v(g);
  for (std::size_t n = 0; n < v.voxels.size(); ++n) v.voxels[n] = float(n) - 50.0f;
  {
    auto f = h5::File::create(tmp / "v.h5");
    auto root = f.root();
    write_volume(root, "hu", v, {"HU", "HU"}, VoxelType::Int16);
    f.close();
  }
  const auto f = h5::File::open(tmp / "v.h5");
  const auto back = read_volume<float>(f.root(), "hu");
  EXPECT_EQ(back.voxels, v.voxels);
  EXPECT_EQ(back.geometry.dims, g.dims);
  EXPECT_EQ(back.geometry.origin, g.origin);
  EXPECT_EQ(back.geometry.spacing, g.spacing);
  EXPECT_EQ(back.geometry.direction, g.direction);
  EXPECT_EQ(f.root().open_group("hu").dataset_type_name("data"), "int16");
  EXPECT_EQ(read_volume_meta(f.root(), "hu").quantity, "HU");
  // Shape on disk: (k, j, i).
  EXPECT_EQ(f.root().open_group("hu").dataset_shape("data"), (std::vector<uint64_t>{3, 5, 7}));
}

TEST(XdmfSidecar, PointsIntoTheHdf5FileWithReversedDims) {
  ImageGeometry g;
  g.dims = {4, 5, 6};
  g.spacing = {1, 2, 3};
  g.origin = {10, 20, 30};
  const auto xml = xdmf_document("ct.h5", {{"ct", g, {{"HU", "/hu/data", VoxelType::Int16}}}});
  EXPECT_NE(xml.find("Dimensions=\"6 5 4\""), std::string::npos);
  EXPECT_NE(xml.find(">30 20 10<"), std::string::npos);
  EXPECT_NE(xml.find(">3 2 1<"), std::string::npos);
  EXPECT_NE(xml.find("ct.h5:/hu/data"), std::string::npos);
  EXPECT_EQ(xdmf_path_for("/a/b/ct.h5"), std::filesystem::path("/a/b/ct.xdmf"));
}

TEST(MemoryGuard, RefusesWhatCannotFit) {
  EXPECT_NO_THROW(check_allocation(1000, 4, "f", "dims"));
  EXPECT_THROW(check_allocation(uint64_t{1} << 62, 8, "f", "dims"), InputError);  // overflows 2^64
  EXPECT_THROW(check_allocation(available_memory_bytes(), 2, "f", "dims"), InputError);
}
