#include "ctsurg/preprocess/image_file_reader.h"

#include "ctsurg/core/error.h"
#include "mhd_writer.h"
#include "nifti_header_peer.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

namespace fs = std::filesystem;
using namespace ctsurg;

namespace {
// Every corner voxel of the ITK geometry against the sform read independently.
void expect_geometry_matches_sform(const fs::path& file) {
  const auto peer = test::read_nifti_peer_header(file);
  const auto info = read_image_file_info(file);
  ASSERT_EQ(info.geometry.dims[0], peer.dims[0]);
  for (int c = 0; c < 8; ++c) {
    const double i = (c & 1) ? peer.dims[0] - 1 : 0, j = (c & 2) ? peer.dims[1] - 1 : 0, k = (c & 4) ? peer.dims[2] - 1 : 0;
    const auto w = info.geometry.index_to_world({i, j, k});
    const auto r = peer.lps(i, j, k);
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(w[a], r[a], 1e-3) << file << " corner " << c;
  }
}
}  // namespace

TEST(ImageFileReader, NiftiGeometryFollowsTheSformLikeThePeer) {
  CTSURG_REQUIRE_SHARED_DATA();
  const auto data = test::shared_data_dir();
  // heart: sform_code 2, qform_code 0; abdomen: int32 voxels, sform only.
  expect_geometry_matches_sform(data / "heart_cta" / "heart_ct.nii.gz");
  expect_geometry_matches_sform(data / "heart_cta" / "heart_mask.nii.gz");
  expect_geometry_matches_sform(data / "abdomen" / "abdomen_ct.nii.gz");
  const auto heart = read_image_file(data / "heart_cta" / "heart_ct.nii.gz");
  const auto [lo, hi] = std::minmax_element(heart.voxels.begin(), heart.voxels.end());
  EXPECT_EQ(*lo, -1064.0f);
  EXPECT_EQ(*hi, 3343.0f);
}

TEST(ImageFileReader, DetachedNrrdWithSpacingsAndSpaceIsRepairedAndReported) {
  CTSURG_REQUIRE_SHARED_DATA();
  const auto header = test::shared_data_dir() / "headsq" / "quarter.nhdr";
  std::vector<std::string> warnings;
  const auto v = read_image_file(header, &warnings);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("spacings"), std::string::npos);
  EXPECT_EQ(v.geometry.dims, (std::array<int64_t, 3>{64, 64, 93}));
  EXPECT_NEAR(v.geometry.spacing[0], 3.2, 1e-9);
  EXPECT_NEAR(v.geometry.spacing[2], 1.5, 1e-9);
  // Voxel values are the raw little-endian shorts of the slice files.
  std::ifstream slice(test::shared_data_dir() / "headsq" / "quarter.40", std::ios::binary);
  std::vector<int16_t> raw(64 * 64);
  slice.read(reinterpret_cast<char*>(raw.data()), raw.size() * 2);
  for (int p = 0; p < 64 * 64; p += 37) EXPECT_EQ(v.voxels[39 * 64 * 64 + p], raw[p]);
}

TEST(ImageFileReader, BadFilesAreInputErrorsNamingTheFileAndField) {
  test::TempDir tmp;
  const auto expect_error = [](const fs::path& p, const std::string& field) {
    try {
      read_image_file(p);
      FAIL() << "no error for " << p;
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), p.string());
      EXPECT_EQ(e.field(), field) << e.what();
    }
  };
  expect_error(tmp / "missing.nii.gz", "");
  expect_error(tmp / "image.png", "file name");
  std::ofstream(tmp / "garbage.nii") << std::string(400, 'x');
  expect_error(tmp / "garbage.nii", "sizeof_hdr");
  std::vector<float> values(8, 1.0f);
  values[5] = std::nanf("");
  expect_error(test::write_mhd(tmp.path(), "nan", 2, 2, 2, values), "voxel data");
  values[5] = INFINITY;
  expect_error(test::write_mhd(tmp.path(), "inf", 2, 2, 2, values), "voxel data");
  values[5] = 0;
  expect_error(test::write_mhd(tmp.path(), "negative", 2, 2, 2, values, "1 -1 1"), "spacing");
  expect_error(test::write_mhd(tmp.path(), "zero", 2, 2, 2, values, "0 1 1"), "spacing");
  // A header that promises more voxels than an image has: bad input.
  const auto huge = tmp / "huge.mhd";
  test::write_mhd(tmp.path(), "huge", 2, 2, 2, values);
  std::ofstream(huge) << "ObjectType = Image\nNDims = 3\nDimSize = 100000 100000 100000\nElementSpacing = 1 1 1\n"
                         "ElementType = MET_FLOAT\nElementDataFile = huge.raw\n";
  expect_error(huge, "DimSize");
  // A complete image (a sparse 100 GB data file) that does not fit in memory: refused before
  // allocating, as a runtime failure (exit 1).
  std::ofstream(tmp / "big.mhd") << "ObjectType = Image\nNDims = 3\nDimSize = 5000 5000 4000\nElementSpacing = 1 1 1\n"
                                    "ElementType = MET_UCHAR\nElementDataFile = big.raw\n";
  { std::ofstream(tmp / "big.raw"); }
  fs::resize_file(tmp / "big.raw", uint64_t{100000000000});
  try {
    read_image_file(tmp / "big.mhd");
    ADD_FAILURE() << "a 100 GB image was read";
  } catch (const InputError& e) {
    ADD_FAILURE() << "a memory refusal is a runtime failure: " << e.what();
  } catch (const RuntimeError& e) {
    EXPECT_NE(std::string(e.what()).find("refused before allocating"), std::string::npos) << e.what();
  }
}
