// ctsurg-surface as a user runs it: an occupancy grid of a ball written with
// write_occupancy_grid_file, then the tool's .h5 / .glb / .stl / .obj outputs, determinism and
// bad-input handling (exit 2, a message naming the problem, no file left behind).
#include "ctsurg/core/hu_volume_file.h"
#include "ctsurg/core/occupancy_grid_file.h"
#include "ctsurg/core/provenance.h"
#include "ctsurg/core/surface_mesh_file.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>

namespace fs = std::filesystem;
using ctsurg::test::run_tool;
using ctsurg::test::TempDir;

namespace {

constexpr double kRadiusMm = 12.0, kCellMm = 2.0;

ctsurg::Provenance test_provenance() { return {"test", "0", {}, {}, nlohmann::json::array()}; }

// A ball of radius 12 mm on 2 mm cells; fractions by 8^3 supersampling; `empty` gives all zeros.
fs::path write_grid(const TempDir& dir, const std::string& name, bool empty = false) {
  ctsurg::ImageGeometry g;
  g.dims = {18, 17, 16};
  g.spacing = Eigen::Vector3d::Constant(kCellMm);
  g.origin = Eigen::Vector3d(-17.0, -16.0, 85.0);
  const Eigen::Vector3d centre = g.index_to_world(Eigen::Vector3d(8.4, 8.1, 7.6));
  ctsurg::OccupancyGrid grid;
  grid.fraction = ctsurg::Volume<float>(g, 0.0f);
  grid.occupancy = ctsurg::Volume<uint8_t>(g, 0);
  grid.label = ctsurg::Volume<uint16_t>(g, 0);
  grid.mask = ctsurg::Volume<uint16_t>(g, 0);
  constexpr int s = 8;
  for (int64_t k = 0; k < g.dims[2] && !empty; ++k)
    for (int64_t j = 0; j < g.dims[1]; ++j)
      for (int64_t i = 0; i < g.dims[0]; ++i) {
        int in = 0;
        for (int c = 0; c < s * s * s; ++c) {
          const Eigen::Vector3d sub((c % s + 0.5) / s - 0.5, ((c / s) % s + 0.5) / s - 0.5, (c / (s * s) + 0.5) / s - 0.5);
          in += (g.index_to_world(Eigen::Vector3d(double(i), double(j), double(k)) + sub) - centre).norm() <= kRadiusMm;
        }
        grid.fraction(i, j, k) = float(in) / (s * s * s);
        grid.occupancy(i, j, k) = grid.fraction(i, j, k) >= 0.5f;
        grid.label(i, j, k) = grid.occupancy(i, j, k);
        grid.mask(i, j, k) = grid.occupancy(i, j, k);
      }
  grid.label_names = {{1, "ball"}};
  const fs::path p = dir / name;
  ctsurg::write_occupancy_grid_file(p, grid, test_provenance());
  return p;
}

std::string read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

bool closed_and_oriented(const ctsurg::SurfaceMesh& m) {
  std::map<std::pair<uint32_t, uint32_t>, int> directed;
  for (std::size_t t = 0; t < m.triangles.size(); t += 3)
    for (std::size_t c = 0; c < 3; ++c) ++directed[{m.triangles[t + c], m.triangles[t + (c + 1) % 3]}];
  for (const auto& [e, n] : directed)
    if (n != 1 || !directed.count({e.second, e.first})) return false;
  return true;
}

double enclosed_volume(const ctsurg::SurfaceMesh& m) {
  double v = 0.0;
  const auto p = [&](uint32_t i) { return Eigen::Vector3d(m.vertices[3 * i], m.vertices[3 * i + 1], m.vertices[3 * i + 2]); };
  for (std::size_t t = 0; t < m.triangles.size(); t += 3)
    v += p(m.triangles[t]).dot(p(m.triangles[t + 1]).cross(p(m.triangles[t + 2]))) / 6.0;
  return v;
}

TEST(CtsurgSurface, GridToSurfaceFileIsClosedAndNearTheBall) {
  TempDir dir;
  const fs::path grid = write_grid(dir, "ball_grid.h5");
  const auto r = run_tool("ctsurg-surface", {grid.string(), (dir / "ball.h5").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("triangles"), std::string::npos) << r.output;
  ASSERT_TRUE(fs::exists(dir / "ball.xdmf"));
  EXPECT_NE(read_bytes(dir / "ball.xdmf").find("TopologyType=\"Triangle\""), std::string::npos);
  const auto m = ctsurg::read_surface_mesh_file(dir / "ball.h5");
  EXPECT_GT(m.triangle_count(), 500);
  EXPECT_TRUE(closed_and_oriented(m));
  const double ball = 4.0 / 3.0 * std::numbers::pi * std::pow(kRadiusMm, 3);
  EXPECT_NEAR(enclosed_volume(m), ball, 0.05 * ball);
  EXPECT_DOUBLE_EQ(m.iso, 0.5);
  EXPECT_EQ(m.quantity, "fraction");
  EXPECT_EQ(m.source_dataset, "/grid/fraction");
  EXPECT_EQ(m.lattice.dims[0], 18);
  EXPECT_DOUBLE_EQ(m.lattice.spacing[0], kCellMm);
  EXPECT_EQ(m.grid_weights.size(), 8 * m.vertices.size() / 3);
}

TEST(CtsurgSurface, ExportsGlbStlObjPly) {
  TempDir dir;
  const fs::path grid = write_grid(dir, "g.h5");
  for (const std::string name : {"s.glb", "s.stl", "s.obj", "s.ply", "s.gltf"}) {
    const auto r = run_tool("ctsurg-surface", {grid.string(), (dir / name).string()});
    ASSERT_EQ(r.exit_code, 0) << name << ": " << r.output;
    ASSERT_GT(fs::file_size(dir / name), 1000u) << name;
  }
  EXPECT_EQ(read_bytes(dir / "s.glb").substr(0, 4), "glTF");
  EXPECT_TRUE(fs::exists(dir / "s.bin"));
  EXPECT_NE(read_bytes(dir / "s.gltf").find("\"s.bin\""), std::string::npos);
  EXPECT_FALSE(fs::exists(dir / "s.mtl"));
  const std::string stl = read_bytes(dir / "s.stl");
  ASSERT_GT(stl.size(), 84u);
  uint32_t facets = 0;
  std::memcpy(&facets, stl.data() + 80, 4);
  EXPECT_EQ(stl.size(), 84u + 50u * facets);
  for (const auto& f : ctsurg::test::files_in(dir.path())) EXPECT_EQ(f.filename().string().rfind(".tmp-", 0), std::string::npos) << f;
}

TEST(CtsurgSurface, RerunIsByteIdentical) {
  TempDir dir;
  const fs::path grid = write_grid(dir, "g.h5");
  const std::vector<std::string> args = {grid.string(), (dir / "s.h5").string(), "--threads", "1"};
  ASSERT_EQ(run_tool("ctsurg-surface", args).exit_code, 0);
  const std::string h5 = read_bytes(dir / "s.h5"), xdmf = read_bytes(dir / "s.xdmf");
  // Another thread count gives the same mesh (only the recorded command line differs).
  ASSERT_EQ(run_tool("ctsurg-surface", {grid.string(), (dir / "t.h5").string(), "--threads", "2"}).exit_code, 0);
  const auto a = ctsurg::read_surface_mesh_file(dir / "s.h5"), b = ctsurg::read_surface_mesh_file(dir / "t.h5");
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_EQ(a.triangles, b.triangles);
  ASSERT_EQ(run_tool("ctsurg-surface", args).exit_code, 0);
  EXPECT_TRUE(read_bytes(dir / "s.h5") == h5);
  EXPECT_TRUE(read_bytes(dir / "s.xdmf") == xdmf);
}

TEST(CtsurgSurface, HuVolumeNeedsIso) {
  TempDir dir;
  ctsurg::HuVolume v;
  ctsurg::ImageGeometry g;
  g.dims = {12, 12, 12};
  v.hu = ctsurg::Volume<float>(g, -1000.0f);
  for (int64_t k = 3; k < 9; ++k)
    for (int64_t j = 3; j < 9; ++j)
      for (int64_t i = 3; i < 9; ++i) v.hu(i, j, k) = 300.0f;
  ctsurg::write_hu_volume_file(dir / "ct.h5", v, test_provenance());
  const auto no_iso = run_tool("ctsurg-surface", {(dir / "ct.h5").string(), (dir / "s.h5").string()});
  EXPECT_EQ(no_iso.exit_code, 2) << no_iso.output;
  EXPECT_NE(no_iso.output.find("--iso"), std::string::npos) << no_iso.output;
  EXPECT_FALSE(fs::exists(dir / "s.h5"));
  const auto ok = run_tool("ctsurg-surface", {(dir / "ct.h5").string(), (dir / "s.h5").string(), "--iso", "150"});
  ASSERT_EQ(ok.exit_code, 0) << ok.output;
  const auto m = ctsurg::read_surface_mesh_file(dir / "s.h5");
  EXPECT_TRUE(closed_and_oriented(m));
  EXPECT_EQ(m.quantity, "HU");
  // The 5 mm cube of inside nodes grown by d = 150/1300 mm on its faces, with chamfered edges and
  // corners: 5^3 + 6 * 5^2 d + 12 * 5 d^2 / 2 + 8 d^3 / 6.
  const double d = 150.0 / 1300.0;
  EXPECT_NEAR(enclosed_volume(m), 125.0 + 150.0 * d + 30.0 * d * d + 8.0 * d * d * d / 6.0, 1e-3);
}

TEST(CtsurgSurface, BadInputExitsTwoAndLeavesNoFile) {
  TempDir dir;
  const fs::path grid = write_grid(dir, "g.h5");
  const fs::path empty = write_grid(dir, "empty.h5", true);
  const auto expect_bad = [&](const std::vector<std::string>& args, const std::string& says) {
    const auto before = ctsurg::test::files_in(dir.path());
    const auto r = run_tool("ctsurg-surface", args);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(says), std::string::npos) << r.output;
    EXPECT_EQ(ctsurg::test::files_in(dir.path()), before) << r.output;
  };
  expect_bad({empty.string(), (dir / "s.h5").string()}, "no surface at iso 0.5");
  expect_bad({grid.string(), (dir / "s.vtk").string()}, "unknown output format");
  expect_bad({(dir / "missing.h5").string(), (dir / "s.h5").string()}, "missing.h5");
  expect_bad({grid.string(), (dir / "no_such_folder" / "s.h5").string()}, "no_such_folder");
  expect_bad({grid.string(), (dir / "s.h5").string(), "--iso", "nan"}, "--iso");
}

}  // namespace
