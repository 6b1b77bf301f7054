// ctsurg-grid as a user runs it: a synthetic HU volume (a +60 HU ball in -1000 HU air) written with
// write_hu_volume_file, then the tool's outputs, determinism and bad-input handling.
#include "ctsurg/core/hu_volume_file.h"
#include "ctsurg/core/occupancy_grid_file.h"
#include "ctsurg/core/provenance.h"
#include "../preprocess/seg_nrrd_writer.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

namespace fs = std::filesystem;
using ctsurg::test::run_tool;
using ctsurg::test::TempDir;

namespace {

constexpr double kRadiusMm = 15.0;

ctsurg::ImageGeometry ct_geometry() {
  ctsurg::ImageGeometry g;
  g.dims = {40, 36, 32};
  g.spacing = Eigen::Vector3d::Constant(1.5);
  g.origin = Eigen::Vector3d(-30.0, -27.0, 100.0);
  return g;
}

// Distance of voxel (i, j, k) from the ball's centre, mm.
double radius_at(const ctsurg::ImageGeometry& g, int64_t i, int64_t j, int64_t k) {
  const Eigen::Vector3d c(19.3, 17.6, 15.8);
  return (g.spacing.cwiseProduct(Eigen::Vector3d(double(i), double(j), double(k)) - c)).norm();
}

using ctsurg::test::test_provenance;

fs::path write_ct(const TempDir& dir) {
  ctsurg::HuVolume v;
  v.hu = ctsurg::Volume<float>(ct_geometry(), -1000.0f);
  const auto& g = v.hu.geometry;
  for (int64_t k = 0; k < g.dims[2]; ++k)
    for (int64_t j = 0; j < g.dims[1]; ++j)
      for (int64_t i = 0; i < g.dims[0]; ++i)
        if (radius_at(g, i, j, k) <= kRadiusMm) v.hu(i, j, k) = 60.0f;
  const fs::path p = dir / "ct.h5";
  ctsurg::write_hu_volume_file(p, v, test_provenance());
  return p;
}

// Labels: 2 in the ball's x < centre half, 3 in the other half.
fs::path write_grid_labels(const TempDir& dir, const ctsurg::ImageGeometry& g, const std::string& name) {
  ctsurg::HuVolume v;
  v.hu = ctsurg::Volume<float>(g, 0.0f);
  for (int64_t k = 0; k < g.dims[2]; ++k)
    for (int64_t j = 0; j < g.dims[1]; ++j)
      for (int64_t i = 0; i < g.dims[0]; ++i)
        if (radius_at(g, i, j, k) <= kRadiusMm) v.hu(i, j, k) = i < 19 ? 2.0f : 3.0f;
  const fs::path p = dir / name;
  ctsurg::write_hu_volume_file(p, v, test_provenance());
  return p;
}

using ctsurg::test::read_bytes;

double tissue_ml(const ctsurg::OccupancyGrid& grid) {
  double s = 0.0;
  for (const float f : grid.fraction.voxels) s += f;
  return s * grid.fraction.geometry.voxel_volume_mm3() / 1000.0;
}

TEST(CtsurgGrid, HuWindowWritesGridXdmfAndPreview) {
  TempDir dir;
  const fs::path ct = write_ct(dir);
  const auto r = run_tool("ctsurg-grid", {ct.string(), (dir / "ball_grid.h5").string(), "--hu-min", "0", "--hu-max", "200",
                                          "--voxel-mm", "2.4", "--fill-holes", "--keep-largest"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("particles"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("mL"), std::string::npos) << r.output;
  ASSERT_TRUE(fs::exists(dir / "ball_grid.xdmf"));
  const std::string png = read_bytes(dir / "ball_grid_preview.png");
  ASSERT_GT(png.size(), 1000u);
  EXPECT_EQ(png.substr(1, 3), "PNG");

  const auto grid = ctsurg::read_occupancy_grid_file(dir / "ball_grid.h5");
  const double analytic_ml = 4.0 / 3.0 * std::numbers::pi * std::pow(kRadiusMm, 3) / 1000.0;  // 14.14 mL
  EXPECT_NEAR(tissue_ml(grid), analytic_ml, 0.03 * analytic_ml);
  EXPECT_NEAR(grid.particle_count() * std::pow(2.4, 3) / 1000.0, analytic_ml, 0.10 * analytic_ml);
  EXPECT_DOUBLE_EQ(grid.occupancy.geometry.spacing[0], 2.4);
  EXPECT_TRUE(grid.mask.geometry.same_lattice(ct_geometry()));
  EXPECT_EQ(grid.label_names, (std::map<uint16_t, std::string>{{1, "tissue"}}));
  EXPECT_DOUBLE_EQ(grid.occupancy_threshold, 0.5);
}

TEST(CtsurgGrid, RerunIsByteIdentical) {
  TempDir dir;
  const fs::path ct = write_ct(dir);
  std::vector<std::string> args = {ct.string(), (dir / "g.h5").string(), "--otsu", "--max-dim", "20"};
  ASSERT_EQ(run_tool("ctsurg-grid", args).exit_code, 0);
  const std::string h5 = read_bytes(dir / "g.h5"), xdmf = read_bytes(dir / "g.xdmf"), png = read_bytes(dir / "g_preview.png");
  ASSERT_EQ(run_tool("ctsurg-grid", args).exit_code, 0);
  EXPECT_TRUE(read_bytes(dir / "g.h5") == h5);
  EXPECT_TRUE(read_bytes(dir / "g.xdmf") == xdmf);
  EXPECT_TRUE(read_bytes(dir / "g_preview.png") == png);
  const auto grid = ctsurg::read_occupancy_grid_file(dir / "g.h5");
  EXPECT_EQ(grid.occupancy.geometry.dims[0], 22);  // 20 cells + margins along the longest axis
}

TEST(CtsurgGrid, MaskFileWithLabelsAndNames) {
  TempDir dir;
  const fs::path ct = write_ct(dir);
  const fs::path labels = write_grid_labels(dir, ct_geometry(), "labels.h5");
  const auto r = run_tool("ctsurg-grid", {ct.string(), labels.string(), (dir / "k.h5").string(), "--labels", "3",
                                          "--label-names", "3=kidney_left", "--voxel-mm", "3", "--no-preview"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_FALSE(fs::exists(dir / "k_preview.png"));
  const auto grid = ctsurg::read_occupancy_grid_file(dir / "k.h5");
  EXPECT_EQ(grid.label_names, (std::map<uint16_t, std::string>{{3, "kidney_left"}}));
  for (const auto v : grid.label.voxels) ASSERT_TRUE(v == 0 || v == 3);
  for (const auto v : grid.mask.voxels) ASSERT_TRUE(v == 0 || v == 3);
  const double analytic_ml = 4.0 / 3.0 * std::numbers::pi * std::pow(kRadiusMm, 3) / 1000.0;
  EXPECT_GT(tissue_ml(grid), 0.35 * analytic_ml);
  EXPECT_LT(tissue_ml(grid), 0.65 * analytic_ml);

  // All labels with a custom preview path: both labels, default names.
  const auto all = run_tool("ctsurg-grid", {ct.string(), labels.string(), (dir / "both.h5").string(), "--voxel-mm", "3",
                                            "--preview", (dir / "p.png").string()});
  ASSERT_EQ(all.exit_code, 0) << all.output;
  EXPECT_TRUE(fs::exists(dir / "p.png"));
  const auto both = ctsurg::read_occupancy_grid_file(dir / "both.h5");
  EXPECT_EQ(both.label_names, (std::map<uint16_t, std::string>{{2, "label_2"}, {3, "label_3"}}));
  EXPECT_NEAR(tissue_ml(both), analytic_ml, 0.03 * analytic_ml);
}

TEST(CtsurgGrid, CellsSmallerThanVoxelsWarnButWork) {
  TempDir dir;
  const fs::path ct = write_ct(dir);
  const auto r = run_tool("ctsurg-grid", {ct.string(), (dir / "fine.h5").string(), "--hu-min", "0", "--voxel-mm", "1.0",
                                          "--no-preview"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("smaller than the CT voxel spacing"), std::string::npos) << r.output;
}

TEST(CtsurgGrid, MaskInAnotherIndexOrderIsReorderedExactlyAndAShiftedOneWarns) {
  TempDir dir;
  const fs::path ct = write_ct(dir);
  const auto reference = run_tool("ctsurg-grid", {ct.string(), write_grid_labels(dir, ct_geometry(), "labels.h5").string(),
                                                  (dir / "a.h5").string(), "--voxel-mm", "3", "--no-preview"});
  ASSERT_EQ(reference.exit_code, 0) << reference.output;
  // The same voxels stored with the rows flipped (as NIfTI exporters write DICOM-derived masks).
  ctsurg::HuVolume flipped;
  flipped.hu = ctsurg::Volume<float>(ct_geometry(), 0.0f);
  auto& fg = flipped.hu.geometry;
  fg.origin = ct_geometry().index_to_world({0, double(fg.dims[1] - 1), 0});
  fg.direction.col(1) *= -1.0;
  const auto g = ct_geometry();
  for (int64_t k = 0; k < g.dims[2]; ++k)
    for (int64_t j = 0; j < g.dims[1]; ++j)
      for (int64_t i = 0; i < g.dims[0]; ++i)
        if (radius_at(g, i, j, k) <= kRadiusMm) flipped.hu(i, g.dims[1] - 1 - j, k) = i < 19 ? 2.0f : 3.0f;
  ctsurg::write_hu_volume_file(dir / "flipped.h5", flipped, test_provenance());
  const auto r = run_tool("ctsurg-grid", {ct.string(), (dir / "flipped.h5").string(), (dir / "b.h5").string(),
                                          "--voxel-mm", "3", "--no-preview"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("reordered exactly"), std::string::npos) << r.output;
  const auto a = ctsurg::read_occupancy_grid_file(dir / "a.h5"), b = ctsurg::read_occupancy_grid_file(dir / "b.h5");
  EXPECT_EQ(a.mask.voxels, b.mask.voxels);
  EXPECT_EQ(a.fraction.voxels, b.fraction.voxels);
  // Half a voxel off: nearest neighbour with a warning that gives the distance.
  ctsurg::ImageGeometry half = ct_geometry();
  half.origin[0] += 0.75;
  const auto w = run_tool("ctsurg-grid", {ct.string(), write_grid_labels(dir, half, "half.h5").string(), (dir / "c.h5").string(),
                                          "--voxel-mm", "3", "--no-preview"});
  ASSERT_EQ(w.exit_code, 0) << w.output;
  EXPECT_NE(w.output.find("nearest neighbour, voxel centres up to 0.75 mm apart"), std::string::npos) << w.output;
}

struct BadCase {
  std::string what;
  std::vector<std::string> args;  // after CT (and, with a mask, before OUTPUT); {MASK} is replaced
  std::string must_mention;
};

// A 3D Slicer segmentation cropped to the ball's box (as Slicer saves it), on two layers: the
// segments' names and values become the grid's labels; --labels picks by value; refusals name the
// file and field.
TEST(CtsurgGrid, SlicerSegmentationLabelsAndNames) {
  TempDir dir;
  const fs::path ct = write_ct(dir);
  const auto g = ct_geometry();
  ctsurg::test::SegNrrd s;
  s.dims = {24, 24, 24};
  s.spacing = {1.5, 1.5, 1.5};
  const Eigen::Vector3d o = g.index_to_world(Eigen::Vector3d(8, 6, 4));
  s.origin = {o[0], o[1], o[2]};
  s.layers = 2;
  s.segments = {{"kidney right", 0, 4}, {"kidney left", 1, 7}};
  s.allocate();
  for (int64_t k = 0; k < 24; ++k)
    for (int64_t j = 0; j < 24; ++j)
      for (int64_t i = 0; i < 24; ++i)
        if (radius_at(g, i + 8, j + 6, k + 4) <= kRadiusMm) s.at(i + 8 < 19 ? 0 : 1, i, j, k) = i + 8 < 19 ? 4 : 7;
  const fs::path seg = dir / "kidneys.seg.nrrd";
  s.write(seg);
  const auto r = run_tool("ctsurg-grid", {ct.string(), seg.string(), (dir / "k.h5").string(), "--voxel-mm", "3", "--no-preview"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto grid = ctsurg::read_occupancy_grid_file(dir / "k.h5");
  EXPECT_EQ(grid.label_names, (std::map<uint16_t, std::string>{{4, "kidney right"}, {7, "kidney left"}}));
  const double analytic_ml = 4.0 / 3.0 * std::numbers::pi * std::pow(kRadiusMm, 3) / 1000.0;
  EXPECT_NEAR(tissue_ml(grid), analytic_ml, 0.03 * analytic_ml);
  const auto left = run_tool("ctsurg-grid", {ct.string(), seg.string(), (dir / "l.h5").string(), "--labels", "7",
                                             "--voxel-mm", "3", "--no-preview"});
  ASSERT_EQ(left.exit_code, 0) << left.output;
  EXPECT_EQ(ctsurg::read_occupancy_grid_file(dir / "l.h5").label_names,
            (std::map<uint16_t, std::string>{{7, "kidney left"}}));

  const auto before = ctsurg::test::files_in(dir.path());
  const auto refused = [&](ctsurg::test::SegNrrd bad, const std::string& must) {
    const fs::path p = dir / "bad.seg.nrrd";
    bad.write(p);
    const auto b = run_tool("ctsurg-grid", {ct.string(), p.string(), (dir / "out.h5").string(), "--no-preview"});
    EXPECT_EQ(b.exit_code, 2) << must << "\n" << b.output;
    EXPECT_NE(b.output.find(must), std::string::npos) << b.output;
    fs::remove(p);
    EXPECT_EQ(ctsurg::test::files_in(dir.path()), before) << must;
  };
  auto overlap = s;
  overlap.at(1, 2, 12, 12) = 7;
  overlap.at(0, 2, 12, 12) = 4;
  refused(overlap, "bad.seg.nrrd: Segment<k>_Layer: the layers overlap: 1 voxels lie in two segments");
  auto missing = s;
  missing.segments[1].write_label_value = false;
  refused(missing, "bad.seg.nrrd: Segment1_LabelValue: absent");
  auto shifted = s;
  shifted.origin[0] += 0.7;
  refused(shifted, "bad.seg.nrrd: space origin: not on a voxel centre of the CT");
  auto fine = s;
  fine.spacing = {1.0, 1.0, 1.0};
  refused(fine, "bad.seg.nrrd: space directions");
  auto duplicate = s;
  duplicate.segments[1].layer = 0;
  duplicate.segments[1].value = 4;
  refused(duplicate, "bad.seg.nrrd: Segment1_LabelValue: 4 is also the label value of Segment0");
}

TEST(CtsurgGrid, BadInputExitsTwoNamesTheProblemAndWritesNothing) {
  TempDir dir;
  const fs::path ct = write_ct(dir);
  ctsurg::ImageGeometry shifted = ct_geometry();
  shifted.origin[0] += 1000.0;  // nowhere near the CT
  const fs::path other = write_grid_labels(dir, shifted, "shifted_labels.h5");
  const fs::path labels = write_grid_labels(dir, ct_geometry(), "labels.h5");
  const auto before = ctsurg::test::files_in(dir.path());
  const std::string out = (dir / "out.h5").string();
  const std::vector<BadCase> cases = {
      {"no selection", {ct.string(), out, "--voxel-mm", "2"}, "selection"},
      {"two selections", {ct.string(), out, "--otsu", "--hu-min", "0"}, "only one"},
      {"mask and window", {ct.string(), labels.string(), out, "--hu-min", "0"}, "only one"},
      {"empty window", {ct.string(), out, "--hu-min", "2000", "--hu-max", "3000"}, "[-1000, 60] HU"},
      {"empty window names it", {ct.string(), out, "--hu-min", "2000", "--hu-max", "3000"}, "[2000, 3000]"},
      {"mask off the lattice", {ct.string(), other.string(), out}, "shifted_labels.h5: geometry: the selected tissue lies outside the CT"},
      {"absent label", {ct.string(), labels.string(), out, "--labels", "7"}, "--labels"},
      {"bad label list", {ct.string(), labels.string(), out, "--labels", "2,x"}, "--labels"},
      {"both sizes", {ct.string(), out, "--otsu", "--voxel-mm", "2", "--max-dim", "50"}, "--voxel-mm"},
      {"negative size", {ct.string(), out, "--otsu", "--voxel-mm", "-1"}, "--voxel-mm"},
      {"zero size", {ct.string(), out, "--otsu", "--voxel-mm", "0"}, "--voxel-mm"},
      {"absurd grid", {ct.string(), out, "--otsu", "--voxel-mm", "0.00001"}, "--voxel-mm"},
      {"bad threshold", {ct.string(), out, "--otsu", "--occupancy-threshold", "0"}, "--occupancy-threshold"},
      {"missing CT", {(dir / "nope.h5").string(), out, "--otsu"}, "nope.h5"},
      {"components too small", {ct.string(), out, "--otsu", "--min-component-mm3", "1e9"}, "--min-component-mm3"},
      // Issue 17: a closing radius of 1e6 mm grew past 2.6 GB with no memory guard.
      {"absurd closing", {ct.string(), out, "--otsu", "--closing-mm", "1e6"}, "--closing-mm"},
      // Issue 17: outputs that are inputs replaced them.
      {"output is the CT", {ct.string(), ct.string(), "--otsu"}, "is the input"},
      {"output is the mask", {ct.string(), labels.string(), labels.string()}, "is the input"},
      {"preview is the grid", {ct.string(), out, "--otsu", "--preview", out}, "is also the output"},
      {"preview is the CT", {ct.string(), out, "--otsu", "--preview", ct.string()}, "is the input"},
  };
  for (const auto& c : cases) {
    const auto r = run_tool("ctsurg-grid", c.args);
    EXPECT_EQ(r.exit_code, 2) << c.what << "\n" << r.output;
    EXPECT_NE(r.output.find(c.must_mention), std::string::npos) << c.what << "\n" << r.output;
    EXPECT_EQ(ctsurg::test::files_in(dir.path()), before) << c.what;
  }
}

// The real heart at 2.4 mm cells: about the papers' pig heart (42,745 particles).
TEST(CtsurgGridRealData, HeartAt2p4mm) {
  CTSURG_REQUIRE_SHARED_DATA();
  TempDir dir;
  const fs::path data = ctsurg::test::shared_data_dir();
  ASSERT_EQ(run_tool("ctsurg-import", {(data / "heart_cta/heart_ct.nii.gz").string(), (dir / "ct.h5").string()}).exit_code, 0);
  const auto r = run_tool("ctsurg-grid", {(dir / "ct.h5").string(), (data / "heart_cta/heart_mask.nii.gz").string(),
                                          (dir / "heart.h5").string(), "--voxel-mm", "2.4", "--label-names", "1=heart"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto grid = ctsurg::read_occupancy_grid_file(dir / "heart.h5");
  EXPECT_NEAR(tissue_ml(grid), 668.84, 0.05);  // 198,176 voxels of 3.375 mm^3
  EXPECT_GT(grid.particle_count(), 42745 * 8 / 10);
  EXPECT_LT(grid.particle_count(), 42745 * 12 / 10);
  EXPECT_TRUE(fs::exists(dir / "heart_preview.png"));
}

// Both kidneys of the upper-abdomen sample (3 mm CT): names, labels, and the volume of the mask.
TEST(CtsurgGridRealData, KidneysWithNames) {
  CTSURG_REQUIRE_SHARED_DATA();
  TempDir dir;
  const fs::path data = ctsurg::test::shared_data_dir() / "abdomen";
  ASSERT_EQ(run_tool("ctsurg-import", {(data / "upper_abdomen_ct.nii.gz").string(), (dir / "ct.h5").string()}).exit_code, 0);
  const auto r = run_tool("ctsurg-grid", {(dir / "ct.h5").string(), (data / "upper_abdomen_labels.nii.gz").string(),
                                          (dir / "kidneys.h5").string(), "--labels", "2,3", "--label-names",
                                          "2=kidney_right,3=kidney_left", "--voxel-mm", "4", "--fill-holes"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto grid = ctsurg::read_occupancy_grid_file(dir / "kidneys.h5");
  EXPECT_EQ(grid.label_names, (std::map<uint16_t, std::string>{{2, "kidney_right"}, {3, "kidney_left"}}));
  int64_t mask_voxels = 0, cells2 = 0, cells3 = 0;
  for (const auto v : grid.mask.voxels) mask_voxels += v != 0;
  for (size_t n = 0; n < grid.label.voxels.size(); ++n) {
    cells2 += grid.occupancy.voxels[n] && grid.label.voxels[n] == 2;
    cells3 += grid.occupancy.voxels[n] && grid.label.voxels[n] == 3;
  }
  EXPECT_NEAR(tissue_ml(grid), mask_voxels * 27.0 / 1000.0, 0.01);
  EXPECT_NEAR(tissue_ml(grid), 205.8, 10.0);  // 7,623 voxels before hole filling
  // Two kidneys of similar size, both kept as bodies.
  EXPECT_GT(cells2, 1000);
  EXPECT_GT(cells3, 1000);
}

}  // namespace

// Issue 17: the grid was committed before its preview was written, so a failed preview exited 1
// with the previous grid already replaced. The grid, its sidecar and the preview are one unit: a
// preview that cannot be written (a file-size limit between the grid's size and the preview's,
// SIGXFSZ ignored) leaves every previous output as it was.
TEST(CtsurgGrid, AFailedPreviewKeepsThePreviousGrid) {
  TempDir dir;
  const fs::path ct = write_ct(dir);
  const std::vector<std::string> args{ct.string(), (dir / "g.h5").string(), "--otsu", "--voxel-mm", "6"};
  ASSERT_EQ(run_tool("ctsurg-grid", args).exit_code, 0);
  const std::string grid = read_bytes(dir / "g.h5"), xdmf = read_bytes(dir / "g.xdmf"), png = read_bytes(dir / "g_preview.png");
  ASSERT_GT(png.size(), grid.size() + 4096) << "the test needs a preview larger than the grid";
  std::string command = "trap '' XFSZ; ulimit -f " + std::to_string((grid.size() + png.size()) / 2 / 1024) +
                        "; CTSURG_NO_PROGRESS=1 " + std::string(CTSURG_TOOL_DIR) + "/ctsurg-grid";
  // Another grid (5 mm cells), so a replaced file would show.
  for (const auto& a : {ct.string(), (dir / "g.h5").string(), std::string("--otsu"), std::string("--voxel-mm"),
                        std::string("5")}) {
    command += " " + a;
  }
  const auto r = ctsurg::test::run_shell(command);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("g_preview.png"), std::string::npos) << r.output;
  EXPECT_TRUE(read_bytes(dir / "g.h5") == grid) << "the previous grid was replaced";
  EXPECT_TRUE(read_bytes(dir / "g.xdmf") == xdmf);
  EXPECT_TRUE(read_bytes(dir / "g_preview.png") == png);
}
