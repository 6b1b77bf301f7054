// 3D Slicer .seg.nrrd files written by hand (seg_nrrd_writer.h): one and two layers merged into one
// label volume with the segments' names and values, and every refusal naming the file and field.
#include "ctsurg/core/error.h"
#include "ctsurg/preprocess/slicer_segmentation.h"
#include "seg_nrrd_writer.h"
#include "test_support.h"

#include <gtest/gtest.h>

using namespace ctsurg;
using ctsurg::test::SegNrrd;
using ctsurg::test::TempDir;

namespace {

// Two segments in one layer: 'liver' (value 1) in i < 2, 'tumour' (value 2) at i = 3.
SegNrrd one_layer() {
  SegNrrd s;
  s.origin = {-10.0, 5.0, 20.0};
  s.spacing = {0.5, 0.75, 2.0};
  s.segments = {{"liver", 0, 1}, {"tumour", 0, 2}};
  s.allocate();
  for (int64_t k = 0; k < 2; ++k)
    for (int64_t j = 0; j < 3; ++j) {
      s.at(0, 0, j, k) = s.at(0, 1, j, k) = 1;
      s.at(0, 3, j, k) = 2;
    }
  return s;
}

// Three segments on two layers; 'vessel' (layer 1, value 1) shares value 1 with 'liver' (layer 0).
SegNrrd two_layers(bool overlap) {
  SegNrrd s = one_layer();
  s.layers = 2;
  s.segments.push_back({"vessel", 1, 1});
  s.allocate();
  for (int64_t k = 0; k < 2; ++k)
    for (int64_t j = 0; j < 3; ++j) {
      s.at(0, 0, j, k) = 1;
      s.at(0, 3, j, k) = 2;
      s.at(1, overlap ? 0 : 2, j, k) = 1;
    }
  return s;
}

std::string refusal(const SegNrrd& s, const TempDir& dir, const std::string& name = "bad.seg.nrrd") {
  const auto p = dir / name;
  s.write(p);
  try {
    read_slicer_segmentation(p);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(read without error)";
}

}  // namespace

TEST(SlicerSegmentation, OneLayerGivesLabelsNamesAndGeometry) {
  TempDir dir;
  const auto p = dir / "a.seg.nrrd";
  one_layer().write(p);
  EXPECT_TRUE(is_slicer_segmentation_file(p));
  EXPECT_TRUE(is_slicer_segmentation_file("X.SEG.NRRD"));
  EXPECT_FALSE(is_slicer_segmentation_file("x.nrrd"));
  const SlicerSegmentation seg = read_slicer_segmentation(p);
  ASSERT_EQ(seg.segments.size(), 2u);
  EXPECT_EQ(seg.segments[1].id, "Segment_2");
  EXPECT_DOUBLE_EQ(seg.segments[0].color[1], 0.7);
  EXPECT_EQ(seg.label_names(), (std::map<uint16_t, std::string>{{1, "liver"}, {2, "tumour"}}));
  const auto& g = seg.labels.geometry;
  EXPECT_EQ(g.dims, (std::array<int64_t, 3>{4, 3, 2}));
  EXPECT_DOUBLE_EQ(g.spacing[1], 0.75);
  EXPECT_DOUBLE_EQ(g.origin[0], -10.0);
  EXPECT_EQ(seg.labels(0, 2, 1), 1);
  EXPECT_EQ(seg.labels(2, 0, 0), 0);
  EXPECT_EQ(seg.labels(3, 1, 1), 2);
}

TEST(SlicerSegmentation, RasSpaceIsConvertedToLps) {
  TempDir dir;
  SegNrrd s = one_layer();
  s.space = "right-anterior-superior";
  s.write(dir / "ras.seg.nrrd");
  const auto g = read_slicer_segmentation(dir / "ras.seg.nrrd").labels.geometry;
  EXPECT_DOUBLE_EQ(g.origin[0], 10.0);
  EXPECT_DOUBLE_EQ(g.origin[1], -5.0);
  EXPECT_DOUBLE_EQ(g.direction(0, 0), -1.0);
  EXPECT_DOUBLE_EQ(g.direction(2, 2), 1.0);
}

TEST(SlicerSegmentation, TwoLayersMergeAndASharedValueIsRenumbered) {
  TempDir dir;
  two_layers(false).write(dir / "b.seg.nrrd");
  std::vector<std::string> warnings;
  const SlicerSegmentation seg = read_slicer_segmentation(dir / "b.seg.nrrd", &warnings);
  ASSERT_EQ(seg.segments.size(), 3u);
  EXPECT_EQ(seg.segments[2].label, 3);  // value 1 in layer 1 -> first free label
  EXPECT_EQ(seg.label_names(), (std::map<uint16_t, std::string>{{1, "liver"}, {2, "tumour"}, {3, "vessel"}}));
  EXPECT_EQ(seg.labels(0, 1, 1), 1);
  EXPECT_EQ(seg.labels(2, 1, 1), 3);
  EXPECT_EQ(seg.labels(3, 1, 1), 2);
  EXPECT_EQ(seg.labels(1, 1, 1), 0);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("Segment2 'vessel'"), std::string::npos) << warnings[0];
}

TEST(SlicerSegmentation, RefusalsNameTheFileAndTheField) {
  TempDir dir;
  // Overlapping layers: 6 voxels in 'liver' and 'vessel'.
  const std::string overlap = refusal(two_layers(true), dir);
  EXPECT_NE(overlap.find("bad.seg.nrrd"), std::string::npos) << overlap;
  EXPECT_NE(overlap.find("6 voxels lie in two segments"), std::string::npos) << overlap;
  EXPECT_NE(overlap.find("Segment0 'liver' and Segment2 'vessel'"), std::string::npos) << overlap;

  SegNrrd missing = two_layers(false);
  missing.segments[2].write_label_value = false;
  EXPECT_NE(refusal(missing, dir).find("bad.seg.nrrd: Segment2_LabelValue: absent"), std::string::npos);

  SegNrrd duplicate = one_layer();
  duplicate.segments[1].value = 1;
  const std::string dup = refusal(duplicate, dir);
  EXPECT_NE(dup.find("Segment1_LabelValue: 1 is also the label value of Segment0"), std::string::npos) << dup;

  SegNrrd bad_layer = one_layer();
  bad_layer.segments[1].layer = 1;
  EXPECT_NE(refusal(bad_layer, dir).find("Segment1_Layer: 1 is not a layer in [0, 0]"), std::string::npos);

  SegNrrd stray = one_layer();
  stray.at(0, 2, 0, 0) = 9;
  EXPECT_NE(refusal(stray, dir).find("data: voxel (2, 0, 0) of layer 0 has value 9"), std::string::npos);

  SegNrrd no_segments = one_layer();
  no_segments.segments.clear();
  EXPECT_NE(refusal(no_segments, dir).find("Segment0_ID"), std::string::npos);

  SegNrrd bad_space = one_layer();
  bad_space.space = "scanner-xyz";
  EXPECT_NE(refusal(bad_space, dir).find("space: 'scanner-xyz'"), std::string::npos);

  SegNrrd truncated = one_layer();
  truncated.voxels.resize(10);
  EXPECT_NE(refusal(truncated, dir).find("data: 10 bytes of voxel data, sizes need 24"), std::string::npos);
}

TEST(SlicerSegmentation, CroppedBoxIsPlacedOnTheCtAndOtherGeometryIsRefused) {
  TempDir dir;
  one_layer().write(dir / "c.seg.nrrd");
  const SlicerSegmentation seg = read_slicer_segmentation(dir / "c.seg.nrrd");
  ImageGeometry ct;
  ct.dims = {10, 8, 6};
  ct.spacing = Eigen::Vector3d(0.5, 0.75, 2.0);
  ct.origin = Eigen::Vector3d(-11.0, 3.5, 16.0);  // the box starts at CT voxel (2, 2, 2)
  const Volume<uint16_t> placed = place_on_lattice(seg.labels, ct, "c.seg.nrrd");
  EXPECT_EQ(placed.geometry.dims, ct.dims);
  EXPECT_EQ(placed(2, 4, 3), 1);
  EXPECT_EQ(placed(5, 2, 2), 2);
  EXPECT_EQ(placed(4, 2, 2), 0);
  int64_t n = 0;
  for (const auto v : placed.voxels) n += v != 0;
  EXPECT_EQ(n, 18);

  const auto message = [&](const ImageGeometry& g) -> std::string {
    try {
      place_on_lattice(seg.labels, g, "c.seg.nrrd");
    } catch (const InputError& e) {
      return e.what();
    }
    return "(placed)";
  };
  ImageGeometry half = ct;
  half.origin[0] += 0.25;
  EXPECT_NE(message(half).find("c.seg.nrrd: space origin: not on a voxel centre of the CT"), std::string::npos);
  ImageGeometry coarse = ct;
  coarse.spacing[2] = 1.0;
  coarse.origin[2] = 20.0;
  EXPECT_NE(message(coarse).find("c.seg.nrrd: space directions"), std::string::npos);
  ImageGeometry small = ct;
  small.dims = {4, 8, 6};
  EXPECT_NE(message(small).find("c.seg.nrrd: sizes: 6 labelled voxels lie outside the CT"), std::string::npos)
      << message(small);
}
