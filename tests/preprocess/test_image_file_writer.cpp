// Tests for preprocess/include/ctsurg/preprocess/image_file_writer.h: round trips through
// image_file_reader.h for every writable format and voxel type, with a rotated, anisotropic,
// off-origin lattice; atomic behaviour; byte-identical reruns.
#include "ctsurg/preprocess/image_file_writer.h"

#include "ctsurg/core/error.h"
#include "ctsurg/preprocess/image_file_reader.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>

namespace fs = std::filesystem;

namespace {

ctsurg::ImageGeometry rotated_geometry() {
  ctsurg::ImageGeometry g;
  g.dims = {7, 5, 4};
  g.spacing = {0.7, 1.1, 2.5};
  g.origin = {-120.25, 33.5, 842.125};
  // A proper rotation about a skew axis: non-identity, orthonormal, no zero entries.
  g.direction = Eigen::AngleAxisd(0.6, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  return g;
}

template <class T>
ctsurg::Volume<T> pattern(const std::function<T(int64_t)>& value) {
  ctsurg::Volume<T> v(rotated_geometry());
  for (std::size_t n = 0; n < v.voxels.size(); ++n) v.voxels[n] = value(static_cast<int64_t>(n));
  return v;
}

void expect_same_geometry(const ctsurg::ImageGeometry& a, const ctsurg::ImageGeometry& b, const std::string& what) {
  EXPECT_EQ(a.dims, b.dims) << what;
  // NIfTI stores spacing, origin and the sform in float32.
  EXPECT_NEAR((a.spacing - b.spacing).norm(), 0, 1e-5) << what;
  EXPECT_NEAR((a.origin - b.origin).norm(), 0, 1e-3) << what;
  EXPECT_NEAR((a.direction - b.direction).norm(), 0, 1e-5) << what << "\n" << b.direction;
  EXPECT_TRUE(a.same_lattice(b, 1e-3)) << what;
}

std::string bytes_of(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

const std::vector<std::string> kSuffixes = {".nii.gz", ".nii", ".nrrd", ".mha"};

TEST(ImageFileWriter, FloatRoundTripKeepsValuesAndRotatedGeometry) {
  ctsurg::test::TempDir dir;
  const auto v = pattern<float>([](int64_t n) { return static_cast<float>(-1000.0 + 13.37 * n - 0.001 * n * n); });
  for (const std::string& suffix : kSuffixes) {
    const fs::path p = dir / ("ct" + suffix);
    ctsurg::write_image_file(v, p);
    const ctsurg::ImageFileInfo info = ctsurg::read_image_file_info(p);
    EXPECT_EQ(info.component_type, "float") << suffix;
    const ctsurg::Volume<float> back = ctsurg::read_image_file(p);
    EXPECT_EQ(back.voxels, v.voxels) << suffix;
    expect_same_geometry(v.geometry, back.geometry, suffix);
    // Voxel (i, j, k) is at the same LPS point: the direction was not transposed or flipped.
    const Eigen::Vector3d ijk(6, 1, 3);
    EXPECT_NEAR((v.geometry.index_to_world(ijk) - back.geometry.index_to_world(ijk)).norm(), 0, 1e-3) << suffix;
  }
}

// NIfTI-1 header: qform_code at byte 252, sform_code at 254 (int16, little-endian here). ITK's
// writer sets both (scanner/aligned), so readers that honour either one see the same geometry.
TEST(ImageFileWriter, NiftiCarriesBothQformAndSform) {
  ctsurg::test::TempDir dir;
  ctsurg::write_image_file(pattern<float>([](int64_t n) { return static_cast<float>(n); }), dir / "ct.nii");
  const std::string header = bytes_of(dir / "ct.nii");
  ASSERT_GE(header.size(), 348u);
  int16_t qform_code = 0, sform_code = 0;
  std::memcpy(&qform_code, header.data() + 252, 2);
  std::memcpy(&sform_code, header.data() + 254, 2);
  EXPECT_GT(qform_code, 0);
  EXPECT_GT(sform_code, 0);
}

TEST(ImageFileWriter, IntegerTypesRoundTripWithTheirOwnStorage) {
  ctsurg::test::TempDir dir;
  const auto hu = pattern<int16_t>([](int64_t n) { return static_cast<int16_t>(-1024 + 37 * n); });
  const auto labels = pattern<uint8_t>([](int64_t n) { return static_cast<uint8_t>(n % 7 == 0 ? 255 : n % 3); });
  const auto big = pattern<uint16_t>([](int64_t n) { return static_cast<uint16_t>(65535 - 401 * n); });
  for (const std::string& suffix : kSuffixes) {
    ctsurg::write_image_file(hu, dir / ("hu" + suffix));
    ctsurg::write_image_file(labels, dir / ("labels" + suffix));
    ctsurg::write_image_file(big, dir / ("big" + suffix));
    EXPECT_EQ(ctsurg::read_image_file_info(dir / ("hu" + suffix)).component_type, "short") << suffix;
    EXPECT_EQ(ctsurg::read_image_file_info(dir / ("labels" + suffix)).component_type, "unsigned_char") << suffix;
    EXPECT_EQ(ctsurg::read_image_file_info(dir / ("big" + suffix)).component_type, "unsigned_short") << suffix;
    const auto hu_back = ctsurg::read_image_file(dir / ("hu" + suffix));
    const auto labels_back = ctsurg::read_image_file(dir / ("labels" + suffix));
    const auto big_back = ctsurg::read_image_file(dir / ("big" + suffix));
    for (std::size_t n = 0; n < hu.voxels.size(); ++n) {
      ASSERT_EQ(hu_back.voxels[n], static_cast<float>(hu.voxels[n])) << suffix << " voxel " << n;
      ASSERT_EQ(labels_back.voxels[n], static_cast<float>(labels.voxels[n])) << suffix << " voxel " << n;
      ASSERT_EQ(big_back.voxels[n], static_cast<float>(big.voxels[n])) << suffix << " voxel " << n;
    }
    expect_same_geometry(hu.geometry, labels_back.geometry, suffix);
  }
}

TEST(ImageFileWriter, LeavesOnlyTheOutputAndReplacesAnExistingFile) {
  ctsurg::test::TempDir dir;
  auto v = pattern<float>([](int64_t n) { return static_cast<float>(n); });
  const fs::path p = dir / "ct.nii.gz";
  { std::ofstream(p) << "old contents"; }
  ctsurg::write_image_file(v, p);
  EXPECT_EQ(ctsurg::test::files_in(dir.path()), std::vector<fs::path>{p});
  EXPECT_EQ(ctsurg::read_image_file(p).voxels, v.voxels);
}

TEST(ImageFileWriter, RewritingGivesIdenticalBytes) {
  ctsurg::test::TempDir dir;
  const auto v = pattern<float>([](int64_t n) { return static_cast<float>(0.25 * n - 3); });
  for (const std::string& suffix : kSuffixes) {
    ctsurg::write_image_file(v, dir / ("a" + suffix));
    ctsurg::write_image_file(v, dir / ("b" + suffix));
    const std::string a = bytes_of(dir / ("a" + suffix)), b = bytes_of(dir / ("b" + suffix));
    EXPECT_FALSE(a.empty()) << suffix;
    EXPECT_EQ(a, b) << suffix;
  }
}

TEST(ImageFileWriter, BadPathsAndVolumesAreRefusedWithoutOutput) {
  ctsurg::test::TempDir dir;
  const auto v = pattern<float>([](int64_t n) { return static_cast<float>(n); });
  EXPECT_THROW(ctsurg::write_image_file(v, dir / "ct.png"), ctsurg::InputError);
  EXPECT_THROW(ctsurg::write_image_file(v, dir / "ct.mhd"), ctsurg::InputError);
  EXPECT_THROW(ctsurg::write_image_file(v, dir / "ct.nhdr"), ctsurg::InputError);
  EXPECT_THROW(ctsurg::write_image_file(v, dir / "missing" / "ct.nii.gz"), ctsurg::InputError);
  EXPECT_THROW(ctsurg::check_image_output_path(dir / "missing" / "ct.nii.gz"), ctsurg::InputError);
  EXPECT_THROW(ctsurg::check_image_output_path(dir / ".nii"), ctsurg::InputError);
  EXPECT_NO_THROW(ctsurg::check_image_output_path(dir / "ct.NII.GZ"));
  auto bad = v;
  bad.geometry.spacing[1] = 0;
  EXPECT_THROW(ctsurg::write_image_file(bad, dir / "ct.nii.gz"), ctsurg::InputError);
  auto short_buffer = v;
  short_buffer.voxels.pop_back();
  EXPECT_THROW(ctsurg::write_image_file(short_buffer, dir / "ct.nii.gz"), ctsurg::RuntimeError);
  EXPECT_TRUE(ctsurg::test::files_in(dir.path()).empty());
}

}  // namespace
