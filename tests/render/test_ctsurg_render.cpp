// ctsurg-render as a user runs it: a surface and a trajectory written by the test, PNG outputs,
// sequences with {}, byte-identical reruns, and bad input (exit 2, a message naming the problem,
// nothing written), and --animation as GIF and MP4 checked with ffprobe.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

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

// Issue 21: --animation as a user runs it, checked with ffprobe (installed with ffmpeg by
// scripts/install-deps.sh; CI has it, so its absence is a failure, not a skip).
namespace {

bool ffmpeg_installed() { return ctsurg::test::run_shell("command -v ffmpeg && command -v ffprobe").exit_code == 0; }
#define CTSURG_REQUIRE_FFMPEG() \
  ASSERT_TRUE(ffmpeg_installed()) << "ffmpeg and ffprobe are not installed: run scripts/install-deps.sh"

struct Probe {
  std::string codec, pix_fmt;
  int width = 0, height = 0;
  long frames = -1;
  std::string frame_rate, raw;
};

// ffprobe's view of the first video stream, its frames counted by decoding them.
Probe ffprobe(const fs::path& file) {
  const auto r = ctsurg::test::run_shell(
      "ffprobe -v error -count_frames -select_streams v:0 -show_entries "
      "stream=codec_name,pix_fmt,width,height,r_frame_rate,nb_read_frames -of default=noprint_wrappers=1 '" + file.string() + "'");
  Probe p;
  p.raw = r.output;
  std::istringstream lines(r.output);
  for (std::string line; std::getline(lines, line);) {
    const auto eq = line.find('=');
    if (eq == std::string::npos) continue;
    const std::string key = line.substr(0, eq), value = line.substr(eq + 1);
    if (key == "codec_name") p.codec = value;
    if (key == "pix_fmt") p.pix_fmt = value;
    if (key == "width") p.width = std::atoi(value.c_str());
    if (key == "height") p.height = std::atoi(value.c_str());
    if (key == "r_frame_rate") p.frame_rate = value;
    if (key == "nb_read_frames") p.frames = std::atol(value.c_str());
  }
  return p;
}

// Six frames from the three-frame scene: the pull ramps up over frames 0..3, then the cut (4, 5).
ctsurg::Trajectory six_frame_trajectory(const ctsurg::SurfaceMesh& s) {
  const ctsurg::Trajectory three = ctsurg::test::three_frame_trajectory(s);
  ctsurg::Trajectory t = three;
  const std::size_t nv = s.vertices.size() / 3;
  const int source[6] = {0, 1, 1, 1, 2, 2};
  const double ramp[6] = {0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0, 1.0, 1.0};
  t.time.clear(), t.vertices.clear(), t.topology_of_frame.clear(), t.spheres.clear(), t.blades.clear();
  t.metrics[0].values.clear();
  for (int f = 0; f < 6; ++f) {
    t.time.push_back(0.2 * f);
    const int k = source[f];
    for (std::size_t i = 0; i < 3 * nv; ++i) {
      const float rest = three.vertices[i], moved = three.vertices[std::size_t(k) * 3 * nv + i];
      t.vertices.push_back(k == 1 ? static_cast<float>(rest + ramp[f] * (moved - rest)) : moved);
    }
    t.topology_of_frame.push_back(three.topology_of_frame[std::size_t(k)]);
    t.spheres.insert(t.spheres.end(), three.spheres.begin() + 4 * k, three.spheres.begin() + 4 * (k + 1));
    t.blades.insert(t.blades.end(), three.blades.begin() + 7 * k, three.blades.begin() + 7 * (k + 1));
    t.metrics[0].values.push_back(three.metrics[0].values[std::size_t(k)]);
  }
  return t;
}

}  // namespace

// Byte-identical reruns are checked on the encoder alone (test_animation_export.cpp).
TEST(CtsurgRender, WritesTrajectoriesAndTurntablesAsMp4AndGif) {
  CTSURG_REQUIRE_FFMPEG();
  Inputs in;
  const fs::path six = in.dir / "six.h5";
  ctsurg::write_trajectory_file(six, six_frame_trajectory(ctsurg::test::bumpy_organ_surface(24, 12, 64)),
                                ctsurg::test::test_provenance());
  struct Case {
    std::string name;
    std::vector<std::string> args;
    int width, height;  // of the pictures; an MP4 rounds odd sides up to even
    long frames;
    std::string frame_rate;
  };
  const std::vector<Case> cases = {
      {"trajectory", {"-s", in.surface.string(), "-t", six.string(), "--frames", "all", "--size", "64x48"}, 64, 48, 6, "10/1"},
      // Odd sides: yuv420p needs even ones, the MP4 gets a black row and column.
      {"turntable", {"-s", in.surface.string(), "--turntable", "5", "--size", "33x25", "--fps", "7.5"}, 33, 25, 5, "15/2"},
  };
  for (const Case& c : cases) {
    for (const std::string suffix : {".mp4", ".gif"}) {
      const fs::path out = in.dir / (c.name + suffix.substr(1));
      fs::create_directory(out);
      const fs::path video = out / (c.name + suffix);
      std::vector<std::string> args = c.args;
      args.insert(args.end(), {"-o", (out / "p_{}.png").string(), "--animation", video.string()});
      const auto r = run_tool("ctsurg-render", args);
      ASSERT_EQ(r.exit_code, 0) << c.name << suffix << ": " << r.output;
      EXPECT_EQ(pngs(out).size(), std::size_t(c.frames)) << c.name;
      const Probe p = ffprobe(video);
      const bool mp4 = suffix == ".mp4";
      EXPECT_EQ(p.codec, mp4 ? "h264" : "gif") << c.name << suffix << ": " << p.raw;
      if (mp4) {
        EXPECT_EQ(p.pix_fmt, "yuv420p") << c.name << ": " << p.raw;
      }
      EXPECT_EQ(p.width, mp4 ? (c.width + 1) / 2 * 2 : c.width) << c.name << suffix << ": " << p.raw;
      EXPECT_EQ(p.height, mp4 ? (c.height + 1) / 2 * 2 : c.height) << c.name << suffix << ": " << p.raw;
      EXPECT_EQ(p.frames, c.frames) << c.name << suffix << ": " << p.raw;
      if (mp4) {
        EXPECT_EQ(p.frame_rate, c.frame_rate) << c.name << ": " << p.raw;
      }
    }
  }
}

TEST(CtsurgRender, ABadAnimationIsRefusedAndAFailedEncodeLeavesNothing) {
  CTSURG_REQUIRE_FFMPEG();
  Inputs in;
  const fs::path out = in.dir / "out";
  fs::create_directory(out);
  const std::string tool = std::string(CTSURG_TOOL_DIR) + "/ctsurg-render -s " + in.surface.string() +
                           " --turntable 2 --size 16 -o " + (out / "p_{}.png").string() + " --animation ";
  // An unknown suffix: exit 2 naming the file and the field, before anything is rendered.
  auto r = ctsurg::test::run_shell(tool + (out / "spin.avi").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("spin.avi: suffix"), std::string::npos) << r.output;
  EXPECT_TRUE(ctsurg::test::files_in(out).empty()) << r.output;
  // No encoder on the PATH: exit 2 naming the encoder and how to install it.
  r = ctsurg::test::run_shell("PATH=" + (in.dir / "empty").string() + " " + tool + (out / "spin.mp4").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("spin.mp4: encoder"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("install-deps.sh"), std::string::npos) << r.output;
  EXPECT_TRUE(ctsurg::test::files_in(out).empty()) << r.output;
  // A failing encoder: exit 1, and the pictures are not committed either.
  const fs::path bin = in.dir / "bin";
  fs::create_directory(bin);
  {
    std::ofstream fake(bin / "ffmpeg");
    fake << "#!/bin/sh\necho 'fake ffmpeg: disk on fire' >&2\nexit 3\n";
  }
  fs::permissions(bin / "ffmpeg", fs::perms::owner_all);
  r = ctsurg::test::run_shell("PATH=" + bin.string() + ":$PATH " + tool + (out / "spin.gif").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("spin.gif: the encoder (ffmpeg) exited with status 3: fake ffmpeg: disk on fire"),
            std::string::npos) << r.output;
  EXPECT_TRUE(ctsurg::test::files_in(out).empty()) << r.output;
}
