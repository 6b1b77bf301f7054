#include "ctsurg/preprocess/ct_import.h"

#include "ctsurg/core/error.h"
#include "mhd_writer.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <fstream>

namespace fs = std::filesystem;
using namespace ctsurg;

TEST(CtImport, DetachedDataFilesResolveAgainstTheHeaderFolder) {
  test::TempDir tmp;
  std::ofstream(tmp / "a.nhdr") << "NRRD0004\ntype: short\ndimension: 3\nsizes: 2 2 3\ndata file: s.%03d 1 5 2\n";
  EXPECT_EQ(detached_data_files(tmp / "a.nhdr"),
            (std::vector<fs::path>{tmp / "s.001", tmp / "s.003", tmp / "s.005"}));
  std::ofstream(tmp / "b.nhdr") << "NRRD0004\ndata file: LIST\nx.raw\ny.raw\n";
  EXPECT_EQ(detached_data_files(tmp / "b.nhdr"), (std::vector<fs::path>{tmp / "x.raw", tmp / "y.raw"}));
  std::ofstream(tmp / "c.nhdr") << "NRRD0004\ndatafile: one.raw.gz\n";
  EXPECT_EQ(detached_data_files(tmp / "c.nhdr"), (std::vector<fs::path>{tmp / "one.raw.gz"}));
  std::ofstream(tmp / "d.mhd") << "NDims = 3\nElementType = MET_SHORT\nElementDataFile = d.raw\n";
  EXPECT_EQ(detached_data_files(tmp / "d.mhd"), (std::vector<fs::path>{tmp / "d.raw"}));
  std::ofstream(tmp / "e.mha") << "NDims = 3\nElementDataFile = LOCAL\n";
  EXPECT_TRUE(detached_data_files(tmp / "e.mha").empty());
}

TEST(CtImport, RescaleOptionsTurnStoredValuesIntoHuAndRawValuesAreFlagged) {
  test::TempDir tmp;
  const std::vector<float> stored{0, 24, 1024, 1084, 2048, 3000, 24, 0};
  const auto file = test::write_mhd(tmp.path(), "raw", 2, 2, 2, stored);
  const auto plain = import_ct(file, {});
  ASSERT_EQ(plain.warnings.size(), 1u);  // all values >= 0 with a high maximum: offset missing?
  EXPECT_NE(plain.warnings[0].find("--rescale-intercept"), std::string::npos);
  CtImportOptions o;
  o.rescale_intercept = -1024.0;
  const auto hu = import_ct(file, o);
  EXPECT_TRUE(hu.warnings.empty());
  EXPECT_EQ(hu.volume.hu.voxels[3], 60.0f);
  EXPECT_EQ(hu.volume.source["hu_min"].get<float>(), -1024.0f);
  EXPECT_EQ(exact_hu_storage(hu.volume.hu), VoxelType::Int16);
  o.rescale_slope = 0.3;  // 24 x 0.3 is not a whole number: stored as float32
  EXPECT_EQ(exact_hu_storage(import_ct(file, o).volume.hu), VoxelType::Float32);
}

TEST(CtImport, MissingInputIsAnInputError) {
  test::TempDir tmp;
  EXPECT_THROW(import_ct(tmp / "nothing.nii.gz", {}), InputError);
  EXPECT_THROW(import_ct(tmp.path(), {}), InputError);  // empty folder: no DICOM
}
