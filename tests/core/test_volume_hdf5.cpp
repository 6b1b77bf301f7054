#include "ctsurg/core/volume_hdf5.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/hdf5_file.h"
#include "ctsurg/core/xdmf_sidecar.h"
#include "test_support.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

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

// Issue 17: NaN never crosses a stage boundary. A float volume with NaN is not written, and one
// that holds NaN (written by another program) is refused naming the voxel.
TEST(VolumeHdf5, NonFiniteVoxelsAreNeitherWrittenNorRead) {
  test::TempDir tmp;
  ImageGeometry g;
  g.dims = {4, 3, 2};
  Volume<float> v(g, 1.0f);
  v(2, 1, 1) = std::nanf("");
  {
    auto f = h5::File::create(tmp / "nan.h5");
    auto root = f.root();
    EXPECT_THROW(write_volume(root, "hu", v, {"HU", "HU"}, VoxelType::Float32), InputError);
  }
  v(2, 1, 1) = 1.0f;
  {
    auto f = h5::File::create(tmp / "v.h5");
    auto root = f.root();
    write_volume(root, "hu", v, {"HU", "HU"}, VoxelType::Float32);
    f.close();
  }
  {  // another writer puts an infinity into the dataset (HDF5 recomputes its checksum)
    const hid_t file = H5Fopen((tmp / "v.h5").c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    const hid_t ds = H5Dopen2(file, "/hu/data", H5P_DEFAULT);
    std::vector<float> values(v.voxels);
    values[static_cast<std::size_t>(g.flat_index(3, 2, 1))] = std::numeric_limits<float>::infinity();
    ASSERT_GE(H5Dwrite(ds, H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), 0);
    H5Dclose(ds);
    H5Fclose(file);
  }
  const auto f = h5::File::open(tmp / "v.h5");
  try {
    read_volume<float>(f.root(), "hu");
    ADD_FAILURE() << "an infinite voxel was read";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "/hu/data");
    EXPECT_NE(e.problem().find("(3, 2, 1)"), std::string::npos) << e.what();
  }
}
