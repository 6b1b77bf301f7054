// The importer against the peer: dcm2niix's reference outputs in ../shared/data/dicom_qa/reference
// and, when installed, dcm2niix itself run on the same series.
#include "ctsurg/preprocess/dicom_series_reader.h"

#include "ctsurg/core/error.h"
#include "ctsurg/preprocess/image_file_reader.h"
#include "ctsurg/preprocess/label_resampling.h"
#include "nifti_header_peer.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>

namespace fs = std::filesystem;
using namespace ctsurg;

namespace {

// Compares an imported series with a dcm2niix NIfTI: dims, in-plane spacing, the world position of
// the corner voxels of the slices in `checked_slices`, and every HU value. dcm2niix stores
// (i, j, k) = (column, Rows-1-row, slice).
void expect_matches_dcm2niix(const Volume<float>& ours, const fs::path& ref_file, const std::vector<int64_t>& checked_slices) {
  const auto peer = test::read_nifti_peer_header(ref_file);
  ASSERT_GT(peer.sform_code, 0);
  const auto& g = ours.geometry;
  ASSERT_EQ(g.dims[0], peer.dims[0]);
  ASSERT_EQ(g.dims[1], peer.dims[1]);
  ASSERT_EQ(g.dims[2], peer.dims[2]);
  EXPECT_NEAR(g.spacing[0], peer.pixdim[0], 1e-5);
  EXPECT_NEAR(g.spacing[1], peer.pixdim[1], 1e-5);
  const int64_t rows = g.dims[1];
  for (int64_t k : checked_slices) {
    for (int64_t j : {int64_t{0}, rows - 1}) {
      for (int64_t i : {int64_t{0}, g.dims[0] - 1}) {
        const Eigen::Vector3d w = g.index_to_world(Eigen::Vector3d(double(i), double(j), double(k)));
        const auto r = peer.lps(double(i), double(rows - 1 - j), double(k));
        // The reference sform is stored in float32: agree to its precision.
        for (int a = 0; a < 3; ++a) EXPECT_NEAR(w[a], r[a], 2e-3) << "voxel " << i << "," << j << "," << k << " axis " << a;
      }
    }
  }
  const Volume<float> ref = read_image_file(ref_file);
  int64_t mismatches = 0;
  for (int64_t k = 0; k < g.dims[2]; ++k)
    for (int64_t j = 0; j < rows; ++j)
      for (int64_t i = 0; i < g.dims[0]; ++i)
        if (ours(i, j, k) != ref(i, rows - 1 - j, k)) ++mismatches;
  EXPECT_EQ(mismatches, 0) << "HU values differ from " << ref_file;
}

fs::path qa() { return test::shared_data_dir() / "dicom_qa"; }

}  // namespace

TEST(DicomSeriesReader, PhilipsUntiltedMatchesDcm2niixReferenceExactly) {
  CTSURG_REQUIRE_SHARED_DATA();
  const auto d = read_dicom_series(qa() / "Philips_S21570_S2010", {});
  EXPECT_TRUE(d.warnings.empty());
  EXPECT_TRUE(d.hu.geometry.is_orthonormal());
  EXPECT_NEAR(d.hu.geometry.spacing[2], 5.0, 1e-6);
  std::vector<int64_t> all;
  for (int64_t k = 0; k < d.hu.geometry.dims[2]; ++k) all.push_back(k);
  expect_matches_dcm2niix(d.hu, qa() / "reference" / "1A_TRAUMA_PLAIN_HEAD_DM_Head_201.nii.gz", all);
  // 12-bit unsigned with RescaleIntercept -1024: air is -1024 HU after rescaling.
  EXPECT_EQ(*std::min_element(d.hu.voxels.begin(), d.hu.voxels.end()), -1024.0f);
}

TEST(DicomSeriesReader, GeTiltedUnevenSeriesIsReportedAndKeptSlicesMatchDcm2niix) {
  CTSURG_REQUIRE_SHARED_DATA();
  DicomReadOptions keep;
  keep.uneven = UnevenSlicePolicy::Keep;
  const auto d = read_dicom_series(qa() / "GE", keep);
  EXPECT_NEAR(d.source["gantry_tilt_deg"].get<double>(), 18.5, 0.05);
  ASSERT_EQ(d.warnings.size(), 2u);
  EXPECT_NE(d.warnings[0].find("gantry tilt of 18.5"), std::string::npos) << d.warnings[0];
  EXPECT_NE(d.warnings[1].find("uneven slice spacing"), std::string::npos) << d.warnings[1];
  // dcm2niix places the first slice exactly (its slice axis comes from the first gap only, so later
  // slices of this uneven series are not where they were scanned; ours follow the positions).
  expect_matches_dcm2niix(d.hu, qa() / "reference" / "_2.nii.gz", {0});
  // The last slice sits at the last ImagePositionPatient (-125, -123.54, 157.776) LPS.
  const Eigen::Vector3d last = d.hu.geometry.index_to_world({0, 0, double(d.hu.geometry.dims[2] - 1)});
  EXPECT_NEAR((last - Eigen::Vector3d(-125.0, -123.5404569, 157.7760586)).norm(), 0.0, 1e-4);
}

TEST(DicomSeriesReader, GeResampledToEvenSlicesKeepsEndSlicesAndExtent) {
  CTSURG_REQUIRE_SHARED_DATA();
  DicomReadOptions keep;
  keep.uneven = UnevenSlicePolicy::Keep;
  const auto kept = read_dicom_series(qa() / "GE", keep);
  const auto even = read_dicom_series(qa() / "GE", {});
  const auto& g = even.hu.geometry;
  EXPECT_LE(g.spacing[2], kept.source["slice_gap_min_mm"].get<double>() + 1e-9);
  const Eigen::Vector3d a = kept.hu.geometry.index_to_world({0, 0, double(kept.hu.geometry.dims[2] - 1)});
  const Eigen::Vector3d b = g.index_to_world({0, 0, double(g.dims[2] - 1)});
  EXPECT_NEAR((a - b).norm(), 0.0, 1e-6);
  const int64_t plane = g.dims[0] * g.dims[1];
  for (int64_t p = 0; p < plane; p += 997) {
    EXPECT_FLOAT_EQ(even.hu.voxels[p], kept.hu.voxels[p]);
    EXPECT_NEAR(even.hu.voxels[(g.dims[2] - 1) * plane + p], kept.hu.voxels[(kept.hu.geometry.dims[2] - 1) * plane + p], 1e-3);
  }
}

TEST(DicomSeriesReader, DecodesJpeg2000Series) {
  CTSURG_REQUIRE_SHARED_DATA();
  const auto d = read_dicom_series(test::shared_data_dir() / "abdomen" / "dicom_j2k", {});
  EXPECT_EQ(d.hu.geometry.dims[0], 512);
  EXPECT_EQ(d.hu.geometry.dims[2], 20);
  EXPECT_NEAR(d.hu.geometry.spacing[2], 2.0, 1e-4);
  // Real anatomy, not zeros: air near -1000 HU and contrast/bone above +300 HU.
  const auto [lo, hi] = std::minmax_element(d.hu.voxels.begin(), d.hu.voxels.end());
  EXPECT_LT(*lo, -900.0f);
  EXPECT_GT(*hi, 300.0f);
  // The TotalSegmentator labels of this series (stored with the rows flipped) land exactly on our
  // voxels, and the geometry is right: liver and spleen (labels 5, 1) are soft tissue, 0..300 HU on average.
  const auto file = read_image_file(test::shared_data_dir() / "abdomen" / "dicom_j2k_labels.nii.gz");
  Volume<uint16_t> stored(file.geometry);
  std::transform(file.voxels.begin(), file.voxels.end(), stored.voxels.begin(), [](float v) { return uint16_t(v); });
  const auto labels = resample_labels_nearest(stored, d.hu.geometry);
  EXPECT_TRUE(labels.exact()) << labels.max_offset_mm;
  EXPECT_EQ(labels.outside, 0);
  double sum = 0;
  int64_t n = 0;
  for (std::size_t v = 0; v < labels.labels.voxels.size(); ++v) {
    if (labels.labels.voxels[v] == 1 || labels.labels.voxels[v] == 5) {
      sum += d.hu.voxels[v];
      ++n;
    }
  }
  ASSERT_GT(n, 1000);
  EXPECT_GT(sum / double(n), 0.0);
  EXPECT_LT(sum / double(n), 300.0);
}

TEST(DicomSeriesReader, MatchesDcm2niixRunNow) {
  CTSURG_REQUIRE_SHARED_DATA();
  const auto which = test::run_shell("command -v dcm2niix");
  if (which.exit_code != 0) GTEST_SKIP() << "dcm2niix not installed";
  test::TempDir tmp;
  const auto r = test::run_shell("dcm2niix -z y -f ref -o '" + tmp.path().string() + "' '" +
                                 (qa() / "Philips_S21570_S2010").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto d = read_dicom_series(qa() / "Philips_S21570_S2010", {});
  std::vector<int64_t> all;
  for (int64_t k = 0; k < d.hu.geometry.dims[2]; ++k) all.push_back(k);
  expect_matches_dcm2niix(d.hu, tmp / "ref.nii.gz", all);
}

TEST(DicomSeriesReader, SeveralSeriesNeedAChoiceAndLocalizersAreSkipped) {
  CTSURG_REQUIRE_SHARED_DATA();
  test::TempDir tmp;
  fs::create_directories(tmp / "a");
  fs::create_directories(tmp / "b");
  for (const auto& e : fs::directory_iterator(qa() / "Philips_S21570_S2010")) fs::copy(e.path(), tmp / "a" / e.path().filename());
  for (const auto& e : fs::directory_iterator(qa() / "GE")) fs::copy(e.path(), tmp / "b" / e.path().filename());
  const auto series = scan_dicom_folder(tmp.path());
  ASSERT_EQ(series.size(), 2u);
  try {
    read_dicom_series(tmp.path(), {});
    FAIL() << "expected an error for two series";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--series"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find(series[0].series_uid), std::string::npos);
  }
  DicomReadOptions pick;
  pick.series = series[1].series_uid;
  EXPECT_EQ(read_dicom_series(tmp.path(), pick).source["series_uid"], series[1].series_uid);
  pick.series = "1.2.3.does.not.exist";
  EXPECT_THROW(read_dicom_series(tmp.path(), pick), InputError);
}
