#include "ctsurg/preprocess/tissue_selection.h"

#include "ctsurg/core/error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace ctsurg {
namespace {

Volume<float> ramp_volume() {
  ImageGeometry g;
  g.dims = {10, 8, 6};
  Volume<float> v(g);
  for (size_t n = 0; n < v.voxels.size(); ++n) v.voxels[n] = float(n % 100) - 50.0f;  // -50 .. 49 HU
  return v;
}

TEST(TissueSelection, HuWindowIsInclusiveAndLabelled) {
  const auto hu = ramp_volume();
  const auto mask = select_hu_window(hu, -10.0, 10.0, "ct.h5", 7);
  int64_t expected = 0;
  for (size_t n = 0; n < hu.voxels.size(); ++n) {
    const bool in = hu.voxels[n] >= -10.0f && hu.voxels[n] <= 10.0f;
    expected += in;
    EXPECT_EQ(mask.voxels[n], in ? 7 : 0);
  }
  EXPECT_EQ(count_tissue_voxels(mask), expected);
  EXPECT_GT(expected, 0);
}

TEST(TissueSelection, EmptyWindowNamesTheWindowAndTheRange) {
  const auto hu = ramp_volume();
  try {
    select_hu_window(hu, 300.0, 500.0, "ct.h5");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("ct.h5"), std::string::npos) << m;
    EXPECT_NE(m.find("[300, 500]"), std::string::npos) << m;
    EXPECT_NE(m.find("[-50, 49]"), std::string::npos) << m;
  }
  EXPECT_THROW(select_hu_window(hu, 10.0, -10.0, "ct.h5"), InputError);
}

// Two Gaussian classes (air-like and tissue-like): Otsu's threshold falls between them, and the
// selection recovers the tissue class almost exactly.
TEST(TissueSelection, OtsuSeparatesTwoClasses) {
  for (const double tissue : {40.0, 300.0, 1200.0}) {
    ImageGeometry g;
    g.dims = {40, 40, 20};
    Volume<float> hu(g);
    std::mt19937 rng(42);
    std::normal_distribution<float> noise(0.0f, 20.0f);
    int64_t truth = 0;
    for (size_t n = 0; n < hu.voxels.size(); ++n) {
      const bool is_tissue = (n / 7) % 3 == 0;
      truth += is_tissue;
      hu.voxels[n] = float(is_tissue ? tissue : -900.0) + noise(rng);
    }
    const double t = otsu_threshold(hu, "ct.h5");
    EXPECT_GT(t, -900.0 + 60.0) << tissue;
    EXPECT_LT(t, tissue - 60.0) << tissue;
    const auto mask = select_otsu(hu, "ct.h5");
    EXPECT_EQ(count_tissue_voxels(mask), truth) << tissue;
  }
}

TEST(TissueSelection, OtsuRejectsConstantVolume) {
  ImageGeometry g;
  g.dims = {4, 4, 4};
  EXPECT_THROW(otsu_threshold(Volume<float>(g, 12.0f), "flat.h5"), InputError);
}

TEST(TissueSelection, LabelsKeepsChosenIdsOrAllNonZero) {
  ImageGeometry g;
  g.dims = {6, 1, 1};
  Volume<float> labels(g);
  labels.voxels = {0, 2, 3, 5, 2, 0};
  const auto all = select_labels(labels, {}, "labels.nii.gz");
  EXPECT_EQ(all.voxels, (std::vector<uint16_t>{0, 2, 3, 5, 2, 0}));
  const auto some = select_labels(labels, {2, 3}, "labels.nii.gz");
  EXPECT_EQ(some.voxels, (std::vector<uint16_t>{0, 2, 3, 0, 2, 0}));
  EXPECT_EQ(labels_present(all), (std::vector<uint16_t>{2, 3, 5}));
}

TEST(TissueSelection, LabelsRejectsBadValuesAndMissingIds) {
  ImageGeometry g;
  g.dims = {3, 1, 1};
  Volume<float> labels(g);
  labels.voxels = {0, 2.5f, 1};
  try {
    select_labels(labels, {}, "labels.nii.gz");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("labels.nii.gz"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("(1, 0, 0)"), std::string::npos) << e.what();
  }
  labels.voxels = {0, 2, 1};
  try {
    select_labels(labels, {9}, "labels.nii.gz");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "--labels");
    EXPECT_NE(std::string(e.what()).find("holds 1 2"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ctsurg
