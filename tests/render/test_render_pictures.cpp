// Golden images of the render stage (render_pictures.h over surface_renderer.h): the normal-mapped
// synthetic organ at rest, grabbed (with the grab sphere), cut (the slit's inside, the blade), and a
// displacement heat map with its colour bar; compared with tests/render/golden/*.png within a stated
// tolerance. Also: the normal map must be visible (ignoring it fails the golden), two renders are
// identical, and sequences share one camera.
//
// Regenerate the goldens (after a deliberate change; look at them before committing):
//   CTSURG_UPDATE_GOLDEN=1 build/bin/test_render --gtest_filter='RenderPictures.*'
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>

#include "ctsurg/core/error.h"
#include "ctsurg/render/render_pictures.h"
#include "ctsurg/render/scene_frame.h"
#include "render_test_scenes.h"
#include "test_support.h"

namespace fs = std::filesystem;

namespace {

// A pixel "differs" when some channel differs by more than kTolerance (out of 255); at most
// kMaxDifferingFraction of the pixels may differ. llvmpipe is deterministic on one machine; the slack
// covers other LLVM versions and vector widths (rounding in the rasteriser's interpolation).
constexpr int kTolerance = 12;
constexpr double kMaxDifferingFraction = 0.01;
constexpr int kSize = 128;

fs::path golden_dir() { return ctsurg::test::source_dir() / "tests" / "render" / "golden"; }

ctsurg::RgbImage render_one(const ctsurg::SurfaceMesh& surface, const ctsurg::Trajectory* trajectory, int64_t frame,
                            ctsurg::Layout layout = ctsurg::Layout::single, bool normal_map = true) {
  ctsurg::RenderModel model{&surface, "organ.h5", trajectory, "organ_trajectory.h5"};
  ctsurg::PictureRequest request;
  request.width = request.height = kSize;
  request.view = ctsurg::parse_view("anterior");
  if (frame >= 0) request.frames = {frame};
  request.layout = layout;
  request.captions = false;
  request.style.normal_map = normal_map;
  // Frame every golden on all three frames, so the pictures line up.
  ctsurg::RgbImage out;
  std::vector<ctsurg::Picture> pictures;
  ctsurg::render_pictures(model, request, [&](ctsurg::Picture&& p) { pictures.push_back(std::move(p)); });
  EXPECT_EQ(pictures.size(), 1u);
  return pictures.empty() ? out : pictures.front().image;
}

void check_golden(const ctsurg::RgbImage& image, const std::string& name) {
  const fs::path path = golden_dir() / name;
  if (std::getenv("CTSURG_UPDATE_GOLDEN")) {
    const std::vector<uint8_t> png = ctsurg::encode_png(image);
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(png.data()), std::streamsize(png.size()));
    std::cout << "updated " << path << "\n";
    return;
  }
  ASSERT_TRUE(fs::exists(path)) << path << " missing: regenerate with CTSURG_UPDATE_GOLDEN=1";
  const ctsurg::RgbImage golden = ctsurg::read_png(path);
  const ctsurg::ImageDifference d = ctsurg::compare_images(image, golden, kTolerance);
  EXPECT_LE(d.fraction_over_tolerance, kMaxDifferingFraction)
      << name << ": " << d.pixels_over_tolerance << " pixels differ by more than " << kTolerance
      << " (max channel difference " << d.max_channel_difference << ", mean " << d.mean_channel_difference << ")";
  if (d.fraction_over_tolerance > kMaxDifferingFraction) {
    const fs::path actual = fs::temp_directory_path() / ("actual_" + name);
    const std::vector<uint8_t> png = ctsurg::encode_png(image);
    std::ofstream(actual, std::ios::binary).write(reinterpret_cast<const char*>(png.data()), std::streamsize(png.size()));
    std::cout << "the rendered picture is in " << actual << "\n";
  }
}

// Pixels that are not the background.
double covered_fraction(const ctsurg::RgbImage& img) {
  const uint8_t* bg = img.pixel(0, 0);
  int64_t n = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const uint8_t* p = img.pixel(x, y);
      n += std::abs(p[0] - bg[0]) + std::abs(p[1] - bg[1]) + std::abs(p[2] - bg[2]) > 12;
    }
  return double(n) / (double(img.width) * img.height);
}

class RenderPictures : public ::testing::Test {
 protected:
  ctsurg::SurfaceMesh surface = ctsurg::test::bumpy_organ_surface();
  ctsurg::Trajectory trajectory = ctsurg::test::three_frame_trajectory(surface);
};

}  // namespace

TEST_F(RenderPictures, RestMatchesGolden) {
  const ctsurg::RgbImage img = render_one(surface, &trajectory, 0);
  EXPECT_GT(covered_fraction(img), 0.3);  // framed: the organ fills much of the picture
  EXPECT_LT(covered_fraction(img), 0.9);
  check_golden(img, "rest.png");
}

TEST_F(RenderPictures, GrabbedMatchesGolden) { check_golden(render_one(surface, &trajectory, 1), "grabbed.png"); }

TEST_F(RenderPictures, CutMatchesGolden) { check_golden(render_one(surface, &trajectory, 2), "cut.png"); }

TEST_F(RenderPictures, HeatMapMatchesGolden) {
  check_golden(render_one(surface, &trajectory, 1, ctsurg::Layout::heat_map), "heat_map.png");
}

TEST_F(RenderPictures, IgnoringTheNormalMapFailsTheGolden) {
  // The detail lives only in the map: without it the rest picture is a smooth ellipsoid, which must
  // not pass for the golden, and must differ clearly from the mapped render.
  const ctsurg::RgbImage with = render_one(surface, &trajectory, 0);
  const ctsurg::RgbImage without = render_one(surface, &trajectory, 0, ctsurg::Layout::single, false);
  const ctsurg::ImageDifference d = ctsurg::compare_images(with, without, kTolerance);
  EXPECT_GT(d.fraction_over_tolerance, 0.1) << "the normal map barely changes the picture";
  if (!std::getenv("CTSURG_UPDATE_GOLDEN")) {
    const ctsurg::RgbImage golden = ctsurg::read_png(golden_dir() / "rest.png");
    EXPECT_GT(ctsurg::compare_images(without, golden, kTolerance).fraction_over_tolerance, kMaxDifferingFraction);
  }
}

TEST_F(RenderPictures, SameInputSamePixels) {
  const ctsurg::RgbImage a = render_one(surface, &trajectory, 2);
  const ctsurg::RgbImage b = render_one(surface, &trajectory, 2);
  EXPECT_EQ(a.rgb, b.rgb);
  EXPECT_EQ(ctsurg::encode_png(a), ctsurg::encode_png(b));
}

TEST_F(RenderPictures, RestFrameEqualsRestSurface) {
  // Frame 0 of the trajectory is the rest shape: the deformed tangent frames reduce to the file's.
  const ctsurg::RgbImage from_trajectory = render_one(surface, &trajectory, 0);
  const ctsurg::RgbImage from_surface = render_one(surface, nullptr, -1);
  const ctsurg::ImageDifference d = ctsurg::compare_images(from_trajectory, from_surface, 2);
  EXPECT_LE(d.fraction_over_tolerance, 0.002);
}

TEST_F(RenderPictures, SideBySideAndOverlayHaveTheRightShape) {
  const ctsurg::RgbImage sbs = render_one(surface, &trajectory, 1, ctsurg::Layout::side_by_side);
  EXPECT_EQ(sbs.width, 2 * kSize + 4);
  EXPECT_EQ(sbs.height, kSize);
  const ctsurg::RgbImage ov = render_one(surface, &trajectory, 1, ctsurg::Layout::overlay);
  EXPECT_EQ(ov.width, kSize);
}

TEST_F(RenderPictures, SequenceTagsAndTurntable) {
  ctsurg::RenderModel model{&surface, "organ.h5", &trajectory, "t.h5"};
  ctsurg::PictureRequest request;
  request.width = request.height = 32;
  request.samples = 1;
  request.view = ctsurg::parse_view("left");
  request.frames = ctsurg::parse_frames("0:2", trajectory.frame_count());
  std::vector<std::string> tags;
  ctsurg::render_pictures(model, request, [&](ctsurg::Picture&& p) { tags.push_back(p.tag); });
  EXPECT_EQ(tags, (std::vector<std::string>{"0000", "0001", "0002"}));
  request.turntable_steps = 4;
  tags.clear();
  ctsurg::render_pictures(model, request, [&](ctsurg::Picture&& p) { tags.push_back(p.tag); });
  EXPECT_EQ(tags, (std::vector<std::string>{"turn000", "turn001", "turn002", "turn003"}));
}

TEST(ParseFrames, SpecsAndErrors) {
  EXPECT_EQ(ctsurg::parse_frames("last", 5), (std::vector<int64_t>{4}));
  EXPECT_EQ(ctsurg::parse_frames("0,2,2,1", 5), (std::vector<int64_t>{0, 1, 2}));
  EXPECT_EQ(ctsurg::parse_frames("0:4:2", 5), (std::vector<int64_t>{0, 2, 4}));
  EXPECT_TRUE(ctsurg::parse_frames("rest", 5).empty());
  EXPECT_THROW(ctsurg::parse_frames("5", 5), ctsurg::InputError);
  EXPECT_THROW(ctsurg::parse_frames("x", 5), ctsurg::InputError);
  EXPECT_THROW(ctsurg::parse_frames("0:3:0", 5), ctsurg::InputError);
}

TEST_F(RenderPictures, MismatchedTrajectoryIsRefused) {
  ctsurg::Trajectory other = trajectory;
  other.rest_vertices.resize(other.rest_vertices.size() - 3);
  ctsurg::RenderModel model{&surface, "organ.h5", &other, "other.h5"};
  ctsurg::PictureRequest request;
  request.frames = {0};
  try {
    ctsurg::render_pictures(model, request, [](ctsurg::Picture&&) {});
    FAIL() << "no error";
  } catch (const ctsurg::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("organ.h5"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("other.h5"), std::string::npos);
  }
}

// Of the pixels where `with` differs from `without` (by more than 12 summed over the channels; counted in
// *changed), how many `is` accepts.
template <class Predicate>
int64_t changed_pixels(const ctsurg::RgbImage& with, const ctsurg::RgbImage& without, int64_t* changed, Predicate is) {
  int64_t accepted = 0;
  *changed = 0;
  for (int y = 0; y < with.height; ++y)
    for (int x = 0; x < with.width; ++x) {
      const uint8_t* a = with.pixel(x, y);
      const uint8_t* b = without.pixel(x, y);
      if (std::abs(a[0] - b[0]) + std::abs(a[1] - b[1]) + std::abs(a[2] - b[2]) <= 12) continue;
      ++*changed;
      accepted += is(a) ? 1 : 0;
    }
  return accepted;
}

// Sutures and closed cuts in the picture of the cut frame: a placed stitch across the slit (in front of
// the surface) is drawn as a violet cylinder, one not yet placed is not drawn; the triangles the
// trajectory marks as closing the cut are drawn in the inside's dark red.
TEST_F(RenderPictures, PlacedStitchesAndClosingTrianglesAreDrawn) {
  const double y = -ctsurg::test::kSceneRadii[1] - 1.0;
  ctsurg::Trajectory t = trajectory;
  t.stitches.assign(3 * 7, 0.0);
  const double stitch[7] = {-6.0, y, 0.0, 6.0, y, 0.0, 1.0};
  for (int f = 0; f < 3; ++f) std::copy(stitch, stitch + 7, t.stitches.begin() + 7 * f);
  t.stitches[7 * 0 + 6] = 0.0;  // frame 0: not placed
  EXPECT_TRUE(ctsurg::trajectory_scene_frame(t, 0).stitch_triangles.empty());
  EXPECT_EQ(ctsurg::trajectory_scene_frame(t, 2).stitch_triangles.size(), 8u * 6 * 6);  // 8 sides, 2 triangles, 6 floats a corner
  const ctsurg::RgbImage without = render_one(surface, &trajectory, 2), with = render_one(surface, &t, 2);
  int64_t changed = 0;
  // Violet, lit or shaded, blended or not at the cylinder's rim: blue over 0.6 of red (the tissue's is
  // about 0.5, the slit's inside 0.2).
  const int64_t violet = changed_pixels(with, without, &changed, [](const uint8_t* a) { return 10 * a[2] > 6 * a[0] && a[2] > a[1]; });
  EXPECT_GT(violet, 10);
  EXPECT_GE(violet, changed * 9 / 10) << changed << " pixels changed, " << violet << " violet";
  // Move the rest topology's triangles facing the camera near the middle to its end and mark them as
  // closing a cut: frame 0 then shows them dark red.
  ctsurg::Trajectory c = trajectory;
  std::vector<uint32_t> front, rest;
  const std::vector<uint32_t>& tri = c.topologies[0];
  for (size_t f = 0; f < tri.size(); f += 3) {
    double m[3] = {0, 0, 0};
    for (int k = 0; k < 3; ++k)
      for (int q = 0; q < 3; ++q) m[q] += surface.vertices[3 * tri[f + static_cast<size_t>(k)] + static_cast<size_t>(q)] / 3.0;
    const bool middle = m[1] < 0 && std::abs(m[0]) < 6 && std::abs(m[2]) < 6;
    (middle ? front : rest).insert((middle ? front : rest).end(), tri.begin() + static_cast<long>(f), tri.begin() + static_cast<long>(f) + 3);
  }
  ASSERT_GT(front.size(), 0u);
  rest.insert(rest.end(), front.begin(), front.end());
  c.topologies[0] = rest;
  c.closing_triangles = {static_cast<int64_t>(front.size() / 3), 0};
  EXPECT_EQ(ctsurg::trajectory_scene_frame(c, 0).closing_triangles, static_cast<int64_t>(front.size() / 3));
  const ctsurg::RgbImage plain = render_one(surface, &trajectory, 0), marked = render_one(surface, &c, 0);
  int64_t darker = 0;
  for (int yy = 0; yy < plain.height; ++yy)
    for (int x = 0; x < plain.width; ++x) darker += marked.pixel(x, yy)[1] + 20 < plain.pixel(x, yy)[1];
  EXPECT_GT(darker, 0);
}

// An instrument in front of the organ (a 6 mm box, active in frame 2 only, turned 45 degrees about the
// view axis): drawn as grey steel where it is, nothing where it is inactive.
TEST_F(RenderPictures, ActiveInstrumentsAreDrawnInSteel) {
  const double y = -ctsurg::test::kSceneRadii[1] - 4.0;  // in front of the anterior surface
  ctsurg::Trajectory t = trajectory;
  ctsurg::TrajectoryInstrument box;
  box.name = "box.stl";
  for (int i = 0; i < 8; ++i) box.vertices.insert(box.vertices.end(), {(i & 1) ? 3.f : -3.f, (i & 2) ? 3.f : -3.f, (i & 4) ? 3.f : -3.f});
  box.triangles = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
  t.instruments = {box};
  const double c = std::cos(M_PI / 8), s = std::sin(M_PI / 8);  // 45 degrees about y (the anterior view's axis)
  for (int f = 0; f < 3; ++f) t.instrument_poses.insert(t.instrument_poses.end(), {f == 2 ? 1.0 : 0.0, c, 0, s, 0, 0, y, 0});
  EXPECT_TRUE(ctsurg::trajectory_scene_frame(t, 1).instrument_triangles.empty());
  EXPECT_EQ(ctsurg::trajectory_scene_frame(t, 2).instrument_triangles.size(), 12u * 3 * 6);  // 12 faces, 3 corners, 6 floats
  const ctsurg::RgbImage without = render_one(surface, &trajectory, 2), with = render_one(surface, &t, 2);
  int64_t changed = 0;
  // Steel: the three channels within a fifth of each other (the tissue is red: green far below red).
  const int64_t grey = changed_pixels(with, without, &changed, [](const uint8_t* a) {
    const int lo = std::min({a[0], a[1], a[2]}), hi = std::max({a[0], a[1], a[2]});
    return hi > 40 && 5 * (hi - lo) < hi;
  });
  EXPECT_GT(grey, 100);
  EXPECT_GE(grey, changed * 8 / 10) << changed << " pixels changed, " << grey << " grey";
  // Inactive in frame 1: the picture is the one without it.
  const ctsurg::RgbImage inactive = render_one(surface, &t, 1), plain = render_one(surface, &trajectory, 1);
  EXPECT_EQ(inactive.rgb, plain.rgb);
}

// The FEM local region (/trajectory/surface/vertex_region): in frame 1 the vertices with x > 8 mm (the
// picture's right half, anterior view) are the region and those with 4 < x <= 8 its interface. The
// single picture changes only right of the centre, mostly towards cyan (the stripes), with a dark
// interface band; the heat map likewise. All flags 0, or RenderStyle::region off, draw the same pixels
// as a trajectory without a region; the legend (captions on) names the run's region_nodes.
TEST_F(RenderPictures, LocalRegionIsHatchedWhereItIsAndNowhereElse) {
  const int64_t nv = trajectory.vertex_count();
  ctsurg::Trajectory t = trajectory;
  t.vertex_region.assign(static_cast<size_t>(3 * nv), 0);
  ctsurg::Trajectory zeros = t;
  for (int64_t v = 0; v < nv; ++v) {
    const float x = surface.vertices[static_cast<size_t>(3 * v)];
    t.vertex_region[static_cast<size_t>(nv + v)] = x > 8.0f ? 1 : x > 4.0f ? 2 : 0;
  }
  EXPECT_EQ(ctsurg::trajectory_scene_frame(trajectory, 1).region, nullptr);
  EXPECT_EQ(ctsurg::trajectory_scene_frame(t, 1).region, t.vertex_region.data() + nv);

  // Pixels that differ, and that all of them lie right of the rendered view's centre column (a heat map's
  // colour bar is appended on the right).
  const auto check_right_only = [&](const ctsurg::RgbImage& with, const ctsurg::RgbImage& without, const char* what) {
    int64_t changed = 0, left = 0, cyan = 0, dark = 0;
    for (int y = 0; y < with.height; ++y)
      for (int x = 0; x < with.width; ++x) {
        const uint8_t* a = with.pixel(x, y);
        const uint8_t* b = without.pixel(x, y);
        if (std::abs(a[0] - b[0]) + std::abs(a[1] - b[1]) + std::abs(a[2] - b[2]) <= 12) continue;
        ++changed;
        left += x < kSize / 2;
        cyan += a[2] > a[0] + 20 && a[1] > a[0] + 20;
        dark += a[0] + a[1] + a[2] + 30 < b[0] + b[1] + b[2];
      }
    EXPECT_GT(changed, with.width * with.height / 20) << what;
    EXPECT_EQ(left, 0) << what << ": the region is right of the centre";
    EXPECT_GT(dark, 20) << what << ": the interface band";
    return cyan;
  };
  const ctsurg::RgbImage plain = render_one(surface, &trajectory, 1), region = render_one(surface, &t, 1);
  const int64_t cyan = check_right_only(region, plain, "single");
  EXPECT_GT(cyan, kSize * kSize / 40) << "the stripes are cyan over the red tissue";
  const ctsurg::RgbImage heat_plain = render_one(surface, &trajectory, 1, ctsurg::Layout::heat_map);
  const ctsurg::RgbImage heat_region = render_one(surface, &t, 1, ctsurg::Layout::heat_map);
  check_right_only(heat_region, heat_plain, "heat map");
  if (const char* dump = std::getenv("CTSURG_DUMP_REGION")) {  // to look at them
    for (const auto& [name, img] : {std::pair{"region_single.png", &region}, std::pair{"region_heat.png", &heat_region}}) {
      const std::vector<uint8_t> png = ctsurg::encode_png(*img);
      std::ofstream(fs::path(dump) / name, std::ios::binary).write(reinterpret_cast<const char*>(png.data()), std::streamsize(png.size()));
    }
  }

  // No region drawn: byte-identical to a trajectory without one.
  EXPECT_EQ(render_one(surface, &zeros, 1).rgb, plain.rgb) << "all flags 0";
  EXPECT_EQ(render_one(surface, &t, 0).rgb, render_one(surface, &trajectory, 0).rgb) << "frame 0 has no region";
  {
    ctsurg::RenderModel model{&surface, "organ.h5", &t, "organ_trajectory.h5"};
    ctsurg::PictureRequest request;
    request.width = request.height = kSize;
    request.view = ctsurg::parse_view("anterior");
    request.frames = {1};
    request.captions = false;
    request.style.region = false;
    ctsurg::render_pictures(model, request, [&](ctsurg::Picture&& p) { EXPECT_EQ(p.image.rgb, plain.rgb) << "region off"; });
    // The legend at the bottom-left (captions on): only there, and only with a region.
    t.metrics.push_back({"region_nodes", "1", {0, 123, 0}});
    request.style.region = true;
    request.captions = true;
    ctsurg::RgbImage with_legend, without_legend;
    ctsurg::render_pictures(model, request, [&](ctsurg::Picture&& p) { with_legend = std::move(p.image); });
    model.trajectory = &trajectory;
    ctsurg::render_pictures(model, request, [&](ctsurg::Picture&& p) { without_legend = std::move(p.image); });
    int64_t legend = 0;
    for (int y = kSize * 3 / 4; y < kSize; ++y)
      for (int x = 0; x < kSize / 2; ++x) legend += with_legend.pixel(x, y)[0] != without_legend.pixel(x, y)[0];
    EXPECT_GT(legend, 50) << "the legend's band at the bottom-left";
  }
}
