// ctsurg-centerline as a user runs it: a label image of a slanted tube (label 3) next to another
// label, then the .h5 + .vtk + preview outputs, byte-identical reruns, bad inputs (exit 2, a message
// naming the field, no file left), and the aorta (label 52) of the shared upper-abdomen labels.
#include "ctsurg/core/centerline_file.h"
#include "ctsurg/preprocess/image_file_writer.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>

namespace fs = std::filesystem;
using ctsurg::test::read_bytes;
using ctsurg::test::run_tool;
using ctsurg::test::TempDir;

namespace {

using Vec = Eigen::Vector3d;

double segment_distance(const Vec& p, const Vec& a, const Vec& b) {
  const Vec d = b - a;
  const double t = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
  return (p - (a + t * d)).norm();
}

// Label 3: a tube of radius 3.5 mm from (5, 6, 5) to (38, 16, 14) mm (0.9 mm voxels); label 7: a
// ball elsewhere; `second_tube` adds a separate piece of label 3.
fs::path write_labels(const TempDir& dir, const std::string& name, bool second_tube = false) {
  ctsurg::ImageGeometry g;
  g.dims = {48, 28, 22};
  g.spacing = Vec(0.9, 0.9, 0.9);
  ctsurg::Volume<uint8_t> v(g, 0);
  for (int64_t k = 0; k < g.dims[2]; ++k)
    for (int64_t j = 0; j < g.dims[1]; ++j)
      for (int64_t i = 0; i < g.dims[0]; ++i) {
        const Vec p = g.index_to_world(Vec(double(i), double(j), double(k)));
        if (segment_distance(p, Vec(5, 6, 5), Vec(38, 16, 14)) <= 3.5) v(i, j, k) = 3;
        if ((p - Vec(8, 20, 14)).norm() <= 3.0) v(i, j, k) = 7;
        if (second_tube && segment_distance(p, Vec(20, 22, 4), Vec(38, 22, 4)) <= 2.0) v(i, j, k) = 3;
      }
  const fs::path path = dir / name;
  ctsurg::write_image_file(v, path);
  return path;
}

TEST(CtsurgCenterline, TubeToCenterlineFileAndPreview) {
  TempDir dir;
  const fs::path labels = write_labels(dir, "labels.nii.gz");
  const auto r = run_tool("ctsurg-centerline", {labels.string(), "--label", "3", "-o", (dir / "c.h5").string(), "--preview",
                                                (dir / "c.png").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("1 branches, 2 nodes"), std::string::npos) << r.output;
  const auto c = ctsurg::read_centerline_file(dir / "c.h5");
  EXPECT_EQ(c.branch_count(), 1);
  EXPECT_EQ(c.label, 3);
  for (std::size_t p = 0; p < c.radius.size(); ++p) {
    const Vec x(c.points[3 * p], c.points[3 * p + 1], c.points[3 * p + 2]);
    EXPECT_LT(segment_distance(x, Vec(5, 6, 5), Vec(38, 16, 14)), 0.9) << p;
  }
  const double mid = c.radius[c.radius.size() / 2];
  EXPECT_NEAR(mid, 3.5, 0.45);
  EXPECT_NE(read_bytes(dir / "c.vtk").find("LINES 1 "), std::string::npos);
  EXPECT_EQ(read_bytes(dir / "c.png").substr(1, 3), "PNG");
  for (const auto& f : ctsurg::test::files_in(dir.path())) EXPECT_EQ(f.filename().string().rfind(".tmp-", 0), std::string::npos) << f;

  // The same input gives the same bytes.
  const std::string h5 = read_bytes(dir / "c.h5"), png = read_bytes(dir / "c.png");
  ASSERT_EQ(run_tool("ctsurg-centerline", {labels.string(), "--label", "3", "-o", (dir / "c.h5").string(), "--preview",
                                           (dir / "c.png").string()})
                .exit_code,
            0);
  EXPECT_TRUE(read_bytes(dir / "c.h5") == h5);
  EXPECT_TRUE(read_bytes(dir / "c.png") == png);
}

TEST(CtsurgCenterline, BadInputExitsTwoAndLeavesNoFile) {
  TempDir dir;
  const fs::path labels = write_labels(dir, "labels.nii.gz");
  const fs::path two = write_labels(dir, "two.nii.gz", true);
  const auto expect_bad = [&](const std::vector<std::string>& args, const std::string& says) {
    const auto before = ctsurg::test::files_in(dir.path());
    const auto r = run_tool("ctsurg-centerline", args);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(says), std::string::npos) << says << "\n" << r.output;
    EXPECT_EQ(ctsurg::test::files_in(dir.path()), before) << r.output;
  };
  const std::string out = (dir / "c.h5").string();
  expect_bad({labels.string(), "-o", out, "--label", "5"}, "label 5 does not occur; values present: 3, 7");
  expect_bad({labels.string(), "-o", out}, "2 separate pieces");  // labels 3 and 7 together
  expect_bad({two.string(), "-o", out, "--label", "3"}, "2 separate pieces");
  expect_bad({labels.string(), "-o", out, "--label", "7"}, "no tubular part");
  expect_bad({labels.string(), "-o", (dir / "c.vtk").string(), "--label", "3"}, "must end in .h5");
  expect_bad({labels.string(), "-o", out, "--label", "3", "--smoothing", "-2"}, "--smoothing");
  expect_bad({(dir / "missing.nii.gz").string(), "-o", out}, "missing.nii.gz");
  // Kept on request: the larger piece.
  const auto r = run_tool("ctsurg-centerline", {two.string(), "-o", out, "--label", "3", "--keep-largest"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(ctsurg::read_centerline_file(out).branch_count(), 1);
}

// The aorta of the shared upper-abdomen labels (TotalSegmentator, 3 mm voxels, 30 slices): one long
// main branch (it crosses the whole field of view), radius of an adult aorta.
TEST(CtsurgCenterline, Aorta) {
  CTSURG_REQUIRE_SHARED_DATA();
  const fs::path labels = ctsurg::test::shared_data_dir() / "abdomen" / "upper_abdomen_labels.nii.gz";
  if (!fs::exists(labels)) GTEST_SKIP() << labels << " absent";
  TempDir dir;
  const auto start = std::chrono::steady_clock::now();
  const auto r = run_tool("ctsurg-centerline", {labels.string(), "--label", "52", "-o", (dir / "aorta.h5").string(),
                                                "--preview", (dir / "aorta.png").string()});
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::printf("%s(%.2f s)\n", r.output.c_str(), seconds);
  const auto c = ctsurg::read_centerline_file(dir / "aorta.h5");
  // The longest branch.
  double longest = 0.0;
  int64_t main = 0;
  for (int64_t b = 0; b < c.branch_count(); ++b) {
    double len = 0.0;
    for (int64_t p = c.branch_offsets[b] + 1; p < c.branch_offsets[b + 1]; ++p) {
      len += (Vec(c.points[3 * p], c.points[3 * p + 1], c.points[3 * p + 2]) -
              Vec(c.points[3 * p - 3], c.points[3 * p - 2], c.points[3 * p - 1]))
                 .norm();
    }
    if (len > longest) {
      longest = len;
      main = b;
    }
  }
  std::printf("aorta: %lld branches, main branch %.1f mm\n", static_cast<long long>(c.branch_count()), longest);
  EXPECT_LE(c.branch_count(), 3);
  EXPECT_GT(longest, 60.0);  // 30 slices of 3 mm: the aorta runs through the whole field of view
  double sum = 0.0;
  int n = 0;
  for (int64_t p = c.branch_offsets[main]; p < c.branch_offsets[main + 1]; ++p, ++n) {
    EXPECT_GT(c.radius[p], 5.0);
    EXPECT_LT(c.radius[p], 20.0);
    sum += c.radius[p];
  }
  std::printf("aorta: mean radius %.2f mm over %d points\n", sum / n, n);
}

}  // namespace
