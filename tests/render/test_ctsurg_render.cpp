// ctsurg-render as a user runs it: a surface and a trajectory written by the test, PNG outputs,
// sequences with {}, byte-identical reruns, and bad input (exit 2, a message naming the problem,
// nothing written).
#include <gtest/gtest.h>

#include "ctsurg/core/file_hash.h"
#include "ctsurg/core/surface_mesh_file.h"
#include "ctsurg/core/trajectory_file.h"
#include "ctsurg/render/rgb_image.h"
#include "render_test_scenes.h"
#include "test_support.h"

namespace fs = std::filesystem;
using ctsurg::test::run_tool;
using ctsurg::test::TempDir;

namespace {

struct Inputs {
  TempDir dir;
  fs::path surface, trajectory, plain_surface;
  Inputs() {
    const ctsurg::SurfaceMesh s = ctsurg::test::bumpy_organ_surface(24, 12, 64);
    surface = dir / "organ.h5";
    ctsurg::write_surface_mesh_file(surface, s, ctsurg::test::test_provenance());
    trajectory = dir / "organ_trajectory.h5";
    ctsurg::write_trajectory_file(trajectory, ctsurg::test::three_frame_trajectory(s), ctsurg::test::test_provenance());
    ctsurg::SurfaceMesh other = ctsurg::test::bumpy_organ_surface(20, 10, 64);
    other.uvs.clear(), other.tangents.clear(), other.source_vertex.clear(), other.source_vertex_count = 0;
    other.normal_map = {};
    plain_surface = dir / "plain.h5";
    ctsurg::write_surface_mesh_file(plain_surface, other, ctsurg::test::test_provenance());
  }
};

std::vector<fs::path> pngs(const fs::path& folder) {
  std::vector<fs::path> out;
  for (const auto& e : fs::recursive_directory_iterator(folder))
    if (e.path().extension() == ".png") out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

TEST(CtsurgRender, RendersFramesAndComparisonsDeterministically) {
  Inputs in;
  const fs::path out = in.dir / "out";
  fs::create_directory(out);
  auto r = run_tool("ctsurg-render", {"-s", in.surface.string(), "-t", in.trajectory.string(), "--frames", "all", "--size",
                                      "64x48", "-o", (out / "f_{}.png").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ASSERT_EQ(pngs(out).size(), 3u);
  const ctsurg::RgbImage img = ctsurg::read_png(out / "f_0001.png");
  EXPECT_EQ(img.width, 64);
  EXPECT_EQ(img.height, 48);
  // The same call again: the same bytes.
  const fs::path again = in.dir / "again";
  fs::create_directory(again);
  r = run_tool("ctsurg-render", {"-s", in.surface.string(), "-t", in.trajectory.string(), "--frames", "all", "--size",
                                 "64x48", "-o", (again / "f_{}.png").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const std::string f : {"f_0000.png", "f_0001.png", "f_0002.png"})
    EXPECT_TRUE(ctsurg::test::read_bytes(again / f) == ctsurg::test::read_bytes(out / f)) << f << " differs between runs";

  for (const std::string layout : {"side-by-side", "overlay", "heat-map"}) {
    r = run_tool("ctsurg-render", {"-s", in.surface.string(), "-t", in.trajectory.string(), "--layout", layout, "--size",
                                   "64", "--view", "30,20", "--projection", "orthographic", "-o",
                                   (out / (layout + ".png")).string()});
    EXPECT_EQ(r.exit_code, 0) << layout << ": " << r.output;
  }
  // Model A against model B (here: the same run twice, as CPU against GPU would be).
  r = run_tool("ctsurg-render", {"-s", in.surface.string(), "-t", in.trajectory.string(), "--layout", "heat-map",
                                 "--reference", in.trajectory.string(), "--size", "64", "-o", (out / "ab.png").string()});
  EXPECT_EQ(r.exit_code, 0) << r.output;
  r = run_tool("ctsurg-render", {"-s", in.surface.string(), "--turntable", "3", "--size", "32", "-o", (out / "t_{}.png").string()});
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(out / "t_turn002.png"));
}

TEST(CtsurgRender, BadInputExitsTwoAndWritesNothing) {
  Inputs in;
  const fs::path out = in.dir / "out";
  fs::create_directory(out);
  const std::string o = (out / "x.png").string();
  struct Case {
    std::vector<std::string> args;
    std::string expect;
  };
  const std::vector<Case> cases = {
      // A trajectory from another surface: names both files and the field.
      {{"-s", in.plain_surface.string(), "-t", in.trajectory.string(), "-o", o}, "rest_vertices"},
      {{"-s", in.surface.string(), "--size", "0", "-o", o}, "--size"},
      {{"-s", in.surface.string(), "--size", "64x0", "-o", o}, "--size"},
      {{"-s", in.surface.string(), "--view", "sideways", "-o", o}, "--view"},
      {{"-s", in.surface.string(), "-t", in.trajectory.string(), "--frames", "7", "-o", o}, "out of range"},
      {{"-s", in.surface.string(), "-t", in.trajectory.string(), "--frames", "all", "-o", o}, "{}"},
      {{"-s", (in.dir / "missing.h5").string(), "-o", o}, "missing.h5"},
      {{"-s", in.trajectory.string(), "-o", o}, "surface_mesh"},
      {{"-s", in.surface.string(), "-o", (out / "x.jpg").string()}, "png"},
      {{"-s", in.surface.string(), "-o", (in.dir / "no" / "x.png").string()}, "no"},
      {{"-s", in.plain_surface.string(), "--layout", "heat-map", "--reference", in.surface.string(), "-o", o}, "same vertices"},
  };
  for (const Case& c : cases) {
    const auto r = run_tool("ctsurg-render", c.args);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(c.expect), std::string::npos) << r.output;
    EXPECT_TRUE(ctsurg::test::files_in(out).empty()) << r.output;
  }
}

TEST(CtsurgRender, MissingNormalMapWarnsAndNoGlContextIsExitTwo) {
  Inputs in;
  const fs::path out = in.dir / "out";
  fs::create_directory(out);
  auto r = run_tool("ctsurg-render", {"-s", in.plain_surface.string(), "--size", "32", "-o", (out / "p.png").string()});
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("no normal map"), std::string::npos) << r.output;
  // No usable OpenGL 4.5: Mesa told to offer at most OpenGL 3.3 cannot create the context.
  r = ctsurg::test::run_shell("MESA_GL_VERSION_OVERRIDE=3.3 " + std::string(CTSURG_TOOL_DIR) +
                              "/ctsurg-render -s " + in.surface.string() + " --size 32 -o " + (out / "q.png").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("OpenGL"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out / "q.png"));
}

// Issue 17: ctsurg-render never checked surface_sha256, although docs/formats.md says it does. A
// trajectory simulated on one surface file is refused on another (here the same mesh written with
// other provenance: other bytes), and drawn on its own.
TEST(CtsurgRender, ATrajectoryIsDrawnOnlyOnTheSurfaceItWasSimulatedOn) {
  Inputs in;
  const ctsurg::SurfaceMesh s = ctsurg::test::bumpy_organ_surface(24, 12, 64);
  ctsurg::Provenance other = ctsurg::test::test_provenance();
  other.command_line.push_back("--another-run");
  ctsurg::write_surface_mesh_file(in.dir / "copy.h5", s, other);
  ctsurg::Trajectory t = ctsurg::test::three_frame_trajectory(s);
  t.surface_sha256 = ctsurg::sha256_file(in.surface);
  ctsurg::write_trajectory_file(in.dir / "t.h5", t, ctsurg::test::test_provenance());
  const auto bad = run_tool("ctsurg-render", {"-s", (in.dir / "copy.h5").string(), "-t", (in.dir / "t.h5").string(), "-o",
                                              (in.dir / "x.png").string(), "--size", "32"});
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("t.h5: /trajectory@surface_sha256"), std::string::npos) << bad.output;
  EXPECT_FALSE(fs::exists(in.dir / "x.png"));
  const auto good = run_tool("ctsurg-render", {"-s", in.surface.string(), "-t", (in.dir / "t.h5").string(), "-o",
                                               (in.dir / "x.png").string(), "--size", "32"});
  EXPECT_EQ(good.exit_code, 0) << good.output;
}

// A trajectory simulated without a surface file (an FEM run: its tet mesh's boundary over the nodes) is
// drawn from its own rest vertices and triangles, without --surface; one that names its surface file
// needs it, and neither a surface nor a trajectory is exit 2 naming --surface.
TEST(CtsurgRender, ATrajectoryWithoutASurfaceFileIsDrawnByItsOwnTriangles) {
  Inputs in;
  ctsurg::Trajectory t = ctsurg::test::three_frame_trajectory(ctsurg::test::bumpy_organ_surface(24, 12, 64));
  t.surface_file.clear();
  ctsurg::write_trajectory_file(in.dir / "own.h5", t, ctsurg::test::test_provenance());
  const auto good = run_tool("ctsurg-render", {"-t", (in.dir / "own.h5").string(), "--layout", "side-by-side", "-o",
                                               (in.dir / "own.png").string(), "--size", "48"});
  ASSERT_EQ(good.exit_code, 0) << good.output;
  const ctsurg::RgbImage img = ctsurg::read_png(in.dir / "own.png");
  EXPECT_EQ(img.width, 2 * 48 + 4);  // rest | last frame, a 4-pixel rule between
  const auto named = run_tool("ctsurg-render", {"-t", in.trajectory.string(), "-o", (in.dir / "x.png").string(), "--size", "32"});
  EXPECT_EQ(named.exit_code, 2) << named.output;
  EXPECT_NE(named.output.find("--surface"), std::string::npos) << named.output;
  EXPECT_FALSE(fs::exists(in.dir / "x.png"));
  const auto neither = run_tool("ctsurg-render", {"-o", (in.dir / "y.png").string()});
  EXPECT_EQ(neither.exit_code, 2) << neither.output;
  EXPECT_NE(neither.output.find("--surface"), std::string::npos) << neither.output;
}
