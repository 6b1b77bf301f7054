// Tests for ctsurg/render/html_viewer.h: the self-contained page (the model as base64 that decodes to
// the .glb, the viewer's script inline, nothing addressed on the network, the title escaped), and the
// page as a user sees it: ctsurg-render --viewer on a cut trajectory of the synthetic organ, opened in
// a real headless Chromium (SwiftShader WebGL, every host name unresolvable) at the first and last frame
// and from the left: the organ drawn in tissue colours, the wound's dark red at the end only, the
// pictures differing between times and views, and no request but the page itself and its blob: URLs.
#include "ctsurg/render/html_viewer.h"

#include <gtest/gtest.h>

#include <cstdlib>

#include "chromium_checks.h"
#include "ctsurg/core/error.h"
#include "ctsurg/render/gltf_animation.h"
#include "ctsurg/render/rgb_image.h"
#include "gltf_animation_scenes.h"
#include "test_support.h"

namespace ctsurg {
namespace {

namespace fs = std::filesystem;

std::string base64_decode(const std::string& text) {
  static const std::string digits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  uint32_t bits = 0;
  int count = 0;
  for (const char c : text) {
    if (c == '=') break;
    const auto d = digits.find(c);
    if (d == std::string::npos) {
      ADD_FAILURE() << "not base64: '" << c << "'";
      return out;
    }
    bits = bits << 6 | static_cast<uint32_t>(d);
    count += 6;
    if (count >= 8) {
      count -= 8;
      out.push_back(static_cast<char>(bits >> count & 255));
    }
  }
  return out;
}

std::size_t occurrences(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(HtmlViewer, ThePageHoldsTheModelAndTheViewerAndAddressesNoNetwork) {
  ASSERT_TRUE(html_viewer_available()) << "the build has no HTML viewer (CTSURG_HTML_VIEWER=OFF)";
  EXPECT_EQ(html_viewer_library().rfind("@google/model-viewer ", 0), 0u) << html_viewer_library();
  const SurfaceMesh surface = test::bumpy_organ_surface(24, 12, 64);
  const Trajectory t = test::bump_trajectory(surface);
  // Lengths 0, 1 and 2 modulo 3 exercise base64's padding.
  std::string glb = export_gltf_animation("m.glb", surface, &t).front().second;
  for (int extra = 0; extra < 3; ++extra, glb.push_back('\x7f')) {
    const std::string page = html_viewer_page(glb, {"<organ & \"co\">", 0.1, 4.0, 0.6});
    // (Found by hand: libstdc++'s std::regex recurses per character, too deep for a megabyte.)
    const std::string open = "id=\"ctsurg-model\" data-time-offset=\"0.1\" data-time-scale=\"4\" data-time-end=\"0.6\">";
    const std::size_t from = page.find(open), to = page.find("</script>", from);
    ASSERT_NE(from, std::string::npos);
    ASSERT_NE(to, std::string::npos);
    EXPECT_TRUE(base64_decode(page.substr(from + open.size(), to - from - open.size())) == glb) << "the embedded model is not the .glb";
    EXPECT_EQ(page.find("@CTSURG_"), std::string::npos) << "a template field left unfilled";
    EXPECT_NE(page.find("<title>&lt;organ &amp; &quot;co&quot;&gt;</title>"), std::string::npos);
    EXPECT_EQ(page.find("<organ"), std::string::npos);
    EXPECT_NE(page.find("Content-Security-Policy\" content=\"default-src 'none';"), std::string::npos);
    // Three script elements (the viewer, the model, the page's own code): the inlined viewer opens and
    // closes none of its own; nothing is loaded from an address.
    EXPECT_EQ(occurrences(page, "<script"), 3u);
    EXPECT_EQ(occurrences(page, "</script>"), 3u);
    for (const std::string attribute : {"src=\"http", "src='http", "src=http", "href=\"http", "href='http", "href=http", "src=\"//", "href=\"//"})
      EXPECT_EQ(page.find(attribute), std::string::npos) << attribute;
    EXPECT_EQ(page.find("<link"), std::string::npos);
    EXPECT_EQ(page.find("sourceMappingURL"), std::string::npos);
  }
  EXPECT_THROW(check_html_viewer_output("page.png"), InputError);
  EXPECT_NO_THROW(check_html_viewer_output("page.HTML"));
}

// Pixels of a screenshot above the page's control bar (the bottom 36 CSS pixels), by kind.
struct PixelCounts {
  int64_t tissue = 0;  // pinkish: red well above green and blue
  int64_t wound = 0;   // dark red: red over 60, green and blue under a third of it
  int64_t total = 0;
};
PixelCounts count_pixels(const RgbImage& img) {
  PixelCounts c;
  for (int y = 0; y < img.height - 40; ++y)
    for (int x = 0; x < img.width; ++x) {
      const uint8_t* p = img.pixel(x, y);
      c.tissue += p[0] > 110 && p[0] > p[1] + 25 && p[0] > p[2] + 25;
      c.wound += p[0] > 60 && 3 * p[1] < p[0] && 3 * p[2] < p[0];
      ++c.total;
    }
  return c;
}

TEST(HtmlViewer, PlaysTheTrajectoryInHeadlessChromium) {
  CTSURG_REQUIRE_CHROMIUM();
  test::TempDir dir;
  const SurfaceMesh surface = test::bumpy_organ_surface(48, 24, 256);
  write_surface_mesh_file(dir / "organ.h5", surface, test::test_provenance());
  write_trajectory_file(dir / "cut.h5", test::cut_trajectory_with_wound(surface), test::test_provenance());
  const auto tool = test::run_tool("ctsurg-render", {"-s", (dir / "organ.h5").string(), "-t", (dir / "cut.h5").string(),
                                                     "--viewer", (dir / "cut viewer.html").string()});
  ASSERT_EQ(tool.exit_code, 0) << tool.output;
  const std::string page = test::file_url(dir / "cut viewer.html");
  // The end (the cut open, its wound), the rest, the rest from the patient's left: one page load, then
  // the address's fragment changed (the page follows it, as a user editing the address would see).
  const auto run = test::chromium_screenshots(
      {{page + "#t=1", dir / "end.png"}, {page + "#t=0", dir / "rest.png"}, {page + "#t=0&orbit=90,0", dir / "left.png"}},
      "window.ctsurgViewer && ((ctsurgViewer.ready && ctsurgViewer.shown === location.hash) || ctsurgViewer.error !== '')",
      "window.ctsurgViewer", 480, 360);
  ASSERT_EQ(run.result.exit_code, 0) << run.result.output;
  EXPECT_TRUE(run.exceptions.empty()) << run.result.output;
  ASSERT_EQ(run.reports.size(), 3u) << run.result.output;
  for (const std::string& r : run.reports) {
    EXPECT_NE(r.find("{\"ready\":true,\"error\":\"\",\"duration\":1.5,\"shown\":\"#t="), std::string::npos) << r;  // 1 s and the hold
  }
  // Nothing but the page and the model's blob: URLs (no http, https, ws or anything with a host).
  ASSERT_FALSE(run.requests.empty());
  for (const std::string& url : run.requests) {
    EXPECT_TRUE(url.rfind("file://", 0) == 0 || url.rfind("blob:", 0) == 0 || url.rfind("data:", 0) == 0) << url;
  }

  const RgbImage rest = read_png(dir / "rest.png"), end = read_png(dir / "end.png"), left = read_png(dir / "left.png");
  ASSERT_EQ(rest.width, 480);
  ASSERT_EQ(rest.height, 360);
  const PixelCounts r = count_pixels(rest), e = count_pixels(end), l = count_pixels(left);
  // The organ fills a good part of the view; the wound shows at the end only, from the front.
  EXPECT_GT(r.tissue, r.total / 10) << "the organ is missing from the picture";
  EXPECT_GT(e.tissue, e.total / 10);
  EXPECT_GT(l.tissue, l.total / 10);
  EXPECT_LT(r.wound, 20);
  EXPECT_GT(e.wound, 100) << "the cut's closing triangles (the wound) are not drawn at the end";
  // Another time and another view give other pictures.
  EXPECT_GT(compare_images(rest, end, 30).fraction_over_tolerance, 0.003);
  EXPECT_GT(compare_images(rest, left, 30).fraction_over_tolerance, 0.02);
  if (std::getenv("CTSURG_DUMP_VIEWER")) {
    for (const char* name : {"rest.png", "end.png", "left.png"})
      fs::copy_file(dir / name, fs::path(std::getenv("CTSURG_DUMP_VIEWER")) / name, fs::copy_options::overwrite_existing);
  }
}

}  // namespace
}  // namespace ctsurg
