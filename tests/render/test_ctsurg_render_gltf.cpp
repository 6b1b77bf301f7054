// ctsurg-render --gltf / --viewer as a user runs them: the animated glTF (.glb, .gltf + .bin) and the HTML
// page besides the pictures or alone, every frame by default (the pictures keep their own default),
// --frames and --time-scale, a surface without a trajectory as a still model, the Khronos validator on
// what was written, and bad usage (exit 2 naming the option or file, nothing written).
#include <gtest/gtest.h>

#include "ctsurg/core/surface_mesh_file.h"
#include "ctsurg/core/trajectory_file.h"
#include "gltf_animation_scenes.h"
#include "gltf_checks.h"
#include "test_support.h"

namespace fs = std::filesystem;
using ctsurg::test::run_tool;

namespace {

struct GltfInputs {
  ctsurg::test::TempDir dir;
  fs::path surface, cut, out;
  GltfInputs() {
    const ctsurg::SurfaceMesh s = ctsurg::test::bumpy_organ_surface(24, 12, 64);
    surface = dir / "organ.h5";
    ctsurg::write_surface_mesh_file(surface, s, ctsurg::test::test_provenance());
    cut = dir / "cut.h5";
    ctsurg::write_trajectory_file(cut, ctsurg::test::cut_trajectory_with_wound(s), ctsurg::test::test_provenance());
    out = dir / "out";
    fs::create_directory(out);
  }
};

// The key times of the first weights channel.
std::vector<float> weight_keys(const ctsurg::test::GltfFile& g) {
  const auto& animation = g.json.at("animations").at(0);
  const auto& sampler = animation.at("samplers").at(animation.at("channels").at(0).at("sampler").get<std::size_t>());
  return g.floats(sampler.at("input").get<std::size_t>());
}

}  // namespace

TEST(CtsurgRenderGltf, WritesTheGltfAndThePageWithThePicturesOrAlone) {
  GltfInputs in;
  // Pictures (the last frame, their default), the whole trajectory as .glb and as .gltf, and the page.
  auto r = run_tool("ctsurg-render", {"-s", in.surface.string(), "-t", in.cut.string(), "--size", "48", "-o",
                                      (in.out / "last.png").string(), "--gltf", (in.out / "cut.glb").string(), "--viewer",
                                      (in.out / "cut.html").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("3 frames, 2 morph targets"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("2 nodes"), std::string::npos) << r.output;
  r = run_tool("ctsurg-render", {"-s", in.surface.string(), "-t", in.cut.string(), "--gltf", (in.out / "cut.gltf").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(ctsurg::test::files_in(in.out),
            (std::vector<fs::path>{in.out / "cut.bin", in.out / "cut.glb", in.out / "cut.gltf", in.out / "cut.html", in.out / "last.png"}));
  EXPECT_TRUE(ctsurg::test::gltf_validates_cleanly({in.out / "cut.glb", in.out / "cut.gltf"}));
  EXPECT_EQ(ctsurg::test::read_gltf(in.out / "cut.glb").json.at("accessors"), ctsurg::test::read_gltf(in.out / "cut.gltf").json.at("accessors"));
  EXPECT_EQ(weight_keys(ctsurg::test::read_gltf(in.out / "cut.glb")), (std::vector<float>{0.0f, 0.5f}));  // node 0: frames 0, 1
  // The page embeds the .glb (as base64: a third larger) and the viewer (about a megabyte).
  EXPECT_GT(fs::file_size(in.out / "cut.html"), fs::file_size(in.out / "cut.glb") * 4 / 3 + 500000);

  // --frames picks the frames, --time-scale stretches the clock; a surface alone is a still model.
  r = run_tool("ctsurg-render", {"-s", in.surface.string(), "-t", in.cut.string(), "--frames", "0,1", "--time-scale", "4",
                                 "--gltf", (in.out / "part.glb").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto part = ctsurg::test::read_gltf(in.out / "part.glb");
  EXPECT_EQ(part.json.at("nodes").size(), 1u);
  EXPECT_EQ(weight_keys(part), (std::vector<float>{0.0f, 2.0f, 4.0f}));  // the last frame held one interval
  r = run_tool("ctsurg-render", {"-s", in.surface.string(), "--gltf", (in.out / "still.glb").string(), "--viewer",
                                 (in.out / "still.html").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_FALSE(ctsurg::test::read_gltf(in.out / "still.glb").json.contains("animations"));
  EXPECT_TRUE(ctsurg::test::gltf_validates_cleanly({in.out / "part.glb", in.out / "still.glb"}));
}

TEST(CtsurgRenderGltf, BadUsageExitsTwoAndWritesNothing) {
  GltfInputs in;
  const std::string s = in.surface.string(), t = in.cut.string();
  struct Case {
    std::vector<std::string> args;
    std::string expect;
  };
  const std::vector<Case> cases = {
      {{"-s", s, "-t", t}, "--output"},
      {{"-s", s, "-t", t, "--gltf", (in.out / "a.obj").string()}, "a.obj: suffix"},
      {{"-s", s, "-t", t, "--viewer", (in.out / "a.txt").string()}, "a.txt: suffix"},
      {{"-s", s, "-t", t, "--gltf", (in.out / "a.glb").string(), "--animation", (in.out / "a.gif").string()}, "--animation"},
      {{"-s", s, "-t", t, "--gltf", (in.out / "a.glb").string(), "--time-scale", "0"}, "--time-scale"},
      {{"-s", s, "-t", t, "--gltf", (in.out / "a.glb").string(), "--frames", "9"}, "out of range"},
      // An output folder that does not exist fails before anything is rendered (no picture is left).
      {{"-s", s, "-t", t, "-o", (in.out / "p.png").string(), "--gltf", (in.dir / "missing" / "a.glb").string()}, "missing"},
      {{"-s", s, "-t", t, "--gltf", (in.out / "a.glb").string(), "--viewer", (in.dir / "missing" / "a.html").string()}, "missing"},
  };
  for (const Case& c : cases) {
    const auto r = run_tool("ctsurg-render", c.args);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(c.expect), std::string::npos) << c.expect << ": " << r.output;
    EXPECT_TRUE(ctsurg::test::files_in(in.out).empty()) << r.output;
  }
}
