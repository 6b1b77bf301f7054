// ctsurg-surface as a user runs it: an occupancy grid of a ball written with
// write_occupancy_grid_file, then the tool's .h5 / .glb / .stl / .obj outputs (glTF: valid by the
// Khronos validator, metres, +Y superior, +Z anterior, faces outward), determinism and bad-input
// handling (exit 2, a message naming the problem, no file left behind). The default surface is
// smoothed (windowed sinc, volume restored), --raw keeps marching cubes' vertices, and no surface the
// tool writes (.h5, .glb, .gltf) has a degenerate triangle (degenerate_triangles.h).
#include "ctsurg/core/hu_volume_file.h"
#include "ctsurg/core/occupancy_grid_file.h"
#include "ctsurg/core/provenance.h"
#include "ctsurg/core/surface_mesh_file.h"
#include "ctsurg/mesh/degenerate_triangles.h"
#include "ctsurg/mesh/gltf_material.h"
#include "gltf_checks.h"
#include "surface_checks.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <hdf5.h>
#include <spdlog/fmt/fmt.h>

#include <Eigen/Geometry>

#include <algorithm>

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

constexpr double kSurfaceRadiusMm = 12.0, kCellMm = 2.0;

using ctsurg::test::test_provenance;

// A ball of radius 12 mm on 2 mm cells; fractions by s^3 supersampling (s = 2: multiples of 1/8,
// many exactly 0.5, like a grid downsampled from a mask); `empty` gives all zeros.
fs::path write_surface_grid(const TempDir& dir, const std::string& name, bool empty = false, int s = 8) {
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
  for (int64_t k = 0; k < g.dims[2] && !empty; ++k)
    for (int64_t j = 0; j < g.dims[1]; ++j)
      for (int64_t i = 0; i < g.dims[0]; ++i) {
        int in = 0;
        for (int c = 0; c < s * s * s; ++c) {
          const Eigen::Vector3d sub((c % s + 0.5) / s - 0.5, ((c / s) % s + 0.5) / s - 0.5, (c / (s * s) + 0.5) / s - 0.5);
          in += (g.index_to_world(Eigen::Vector3d(double(i), double(j), double(k)) + sub) - centre).norm() <= kSurfaceRadiusMm;
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

using ctsurg::test::read_bytes;

bool closed_and_oriented(const ctsurg::SurfaceMesh& m) { return ctsurg::test::manifold_problem(m).empty(); }
using ctsurg::test::enclosed_volume;

// Degenerate triangles (degenerate_triangles.h) of a surface file, "" when there is none.
std::string degenerate(const ctsurg::SurfaceMesh& m) {
  const ctsurg::DegenerateTriangleCount n = ctsurg::count_degenerate_triangles(m, ctsurg::lattice_cell_mm(m));
  return n.total() == 0 ? "" : n.summary();
}

// The same for a .glb/.gltf the tool wrote from a lattice of cell `cell_mm`: its POSITION and
// indices as written (metres, after the exporter joined identical vertices, so a repeated index
// shows here), against the cell in metres.
std::string degenerate_gltf(const fs::path& path, double cell_mm) {
  const auto gltf = ctsurg::test::read_gltf(path);
  ctsurg::SurfaceMesh m;
  m.vertices = gltf.floats(gltf.attribute("POSITION"));
  m.triangles = gltf.indices(gltf.json.at("meshes").at(0).at("primitives").at(0).at("indices").get<std::size_t>());
  if (m.triangles.empty()) return "no triangles";
  const ctsurg::DegenerateTriangleCount n = ctsurg::count_degenerate_triangles(m, cell_mm / 1000.0);
  return n.total() == 0 ? "" : n.summary();
}

// Mean angle (degrees) between the vertex normals and the direction from `centre` (LPS mm).
double mean_normal_error_deg(const ctsurg::SurfaceMesh& m, const Eigen::Vector3d& centre) {
  double sum = 0.0;
  for (int64_t v = 0; v < m.vertex_count(); ++v) {
    const auto i = static_cast<std::size_t>(v);
    const Eigen::Vector3d n(m.normals[3 * i], m.normals[3 * i + 1], m.normals[3 * i + 2]);
    const Eigen::Vector3d r = (ctsurg::test::vertex(m, static_cast<uint32_t>(v)) - centre).normalized();
    sum += std::acos(std::clamp(n.normalized().dot(r), -1.0, 1.0)) * 180.0 / std::numbers::pi;
  }
  return sum / double(m.vertex_count());
}

// A 12^3 HU volume with a 6^3 block of 300 HU in air; `at_border` puts the block against the
// volume's i = 0 face.
fs::path write_block_ct(const TempDir& dir, bool at_border) {
  ctsurg::HuVolume v;
  ctsurg::ImageGeometry g;
  g.dims = {12, 12, 12};
  v.hu = ctsurg::Volume<float>(g, -1000.0f);
  const int64_t i0 = at_border ? 0 : 3;
  for (int64_t k = 3; k < 9; ++k)
    for (int64_t j = 3; j < 9; ++j)
      for (int64_t i = i0; i < i0 + 6; ++i) v.hu(i, j, k) = 300.0f;
  const fs::path p = dir / (at_border ? "border_ct.h5" : "ct.h5");
  ctsurg::write_hu_volume_file(p, v, test_provenance());
  return p;
}

TEST(CtsurgSurface, GridToSurfaceFileIsClosedAndNearTheBall) {
  TempDir dir;
  const fs::path grid = write_surface_grid(dir, "ball_grid.h5");
  const auto r = run_tool("ctsurg-surface", {grid.string(), (dir / "ball.h5").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("triangles"), std::string::npos) << r.output;
  ASSERT_TRUE(fs::exists(dir / "ball.xdmf"));
  EXPECT_NE(read_bytes(dir / "ball.xdmf").find("TopologyType=\"Triangle\""), std::string::npos);
  const auto m = ctsurg::read_surface_mesh_file(dir / "ball.h5");
  EXPECT_GT(m.triangle_count(), 500);
  EXPECT_TRUE(closed_and_oriented(m));
  const double ball = 4.0 / 3.0 * std::numbers::pi * std::pow(kSurfaceRadiusMm, 3);
  EXPECT_NEAR(enclosed_volume(m), ball, 0.05 * ball);
  EXPECT_DOUBLE_EQ(m.iso, 0.5);
  EXPECT_EQ(m.quantity, "fraction");
  EXPECT_EQ(m.source_dataset, "/grid/fraction");
  EXPECT_EQ(m.lattice.dims[0], 18);
  EXPECT_DOUBLE_EQ(m.lattice.spacing[0], kCellMm);
  EXPECT_EQ(m.grid_weights.size(), 8 * m.vertices.size() / 3);
  EXPECT_EQ(degenerate(m), "");
}

// The default surface is smoothed (windowed sinc, 20 iterations) with marching cubes' volume kept;
// --raw (as --smooth 0) keeps marching cubes' vertices, each on a lattice edge. Neither has a
// degenerate triangle, in the .h5 or in the .glb, although this ball's grid has fractions exactly at
// 0.5, so that marching cubes alone leaves coincident vertices.
TEST(CtsurgSurface, DefaultIsSmoothedRawIsMarchingCubesAndNoneHasDegenerateTriangles) {
  TempDir dir;
  const fs::path grid = write_surface_grid(dir, "g.h5", false, 2);
  const auto smoothed = run_tool("ctsurg-surface", {grid.string(), (dir / "s.h5").string()});
  ASSERT_EQ(smoothed.exit_code, 0) << smoothed.output;
  EXPECT_NE(smoothed.output.find("windowed-sinc 20 iterations"), std::string::npos) << smoothed.output;
  EXPECT_NE(smoothed.output.find("restored"), std::string::npos) << smoothed.output;
  EXPECT_NE(smoothed.output.find("degenerate triangles: "), std::string::npos) << smoothed.output;
  EXPECT_EQ(smoothed.output.find("degenerate triangles: 0 ("), std::string::npos) << smoothed.output;
  const auto raw = run_tool("ctsurg-surface", {grid.string(), (dir / "r.h5").string(), "--raw"});
  ASSERT_EQ(raw.exit_code, 0) << raw.output;
  EXPECT_EQ(raw.output.find("smoothed"), std::string::npos) << raw.output;
  ASSERT_EQ(run_tool("ctsurg-surface", {grid.string(), (dir / "z.h5").string(), "--smooth", "0"}).exit_code, 0);
  ASSERT_EQ(run_tool("ctsurg-surface", {grid.string(), (dir / "t.h5").string(), "--smooth-method", "taubin"}).exit_code, 0);
  const auto s = ctsurg::read_surface_mesh_file(dir / "s.h5"), r = ctsurg::read_surface_mesh_file(dir / "r.h5");
  const auto z = ctsurg::read_surface_mesh_file(dir / "z.h5"), t = ctsurg::read_surface_mesh_file(dir / "t.h5");
  EXPECT_EQ(r.vertices, z.vertices);
  EXPECT_EQ(r.triangles, z.triangles);
  EXPECT_EQ(s.triangles, r.triangles);  // smoothing moves vertices only
  EXPECT_NE(s.vertices, r.vertices);
  EXPECT_NE(t.vertices, s.vertices);
  for (const auto* m : {&s, &r, &t}) {
    EXPECT_TRUE(closed_and_oriented(*m));
    EXPECT_EQ(degenerate(*m), "");
  }
  // Raw vertices sit on lattice edges (two integer index coordinates); smoothed ones mostly do not.
  const auto on_edges = [](const ctsurg::SurfaceMesh& m) {
    int64_t n = 0;
    for (int64_t v = 0; v < m.vertex_count(); ++v) {
      const Eigen::Vector3d ijk = m.lattice.world_to_index(ctsurg::test::vertex(m, static_cast<uint32_t>(v)));
      int integer = 0;
      for (int a = 0; a < 3; ++a) integer += std::abs(ijk[a] - std::round(ijk[a])) < 1e-4;
      n += integer >= 2;
    }
    return double(n) / double(m.vertex_count());
  };
  EXPECT_EQ(on_edges(r), 1.0);
  EXPECT_LT(on_edges(s), 0.1);
  // The volume is marching cubes' (restored after smoothing), the normals closer to the ball's.
  EXPECT_NEAR(enclosed_volume(s) / enclosed_volume(r), 1.0, 1e-6);
  EXPECT_NEAR(enclosed_volume(t) / enclosed_volume(r), 1.0, 1e-6);
  const Eigen::Vector3d centre = r.lattice.index_to_world(Eigen::Vector3d(8.4, 8.1, 7.6));
  EXPECT_LT(mean_normal_error_deg(s, centre), 0.7 * mean_normal_error_deg(r, centre));
  // The glTF files the same way, as written (Assimp joins identical vertices).
  for (const std::string name : {"s.glb", "r.glb", "s.gltf"}) {
    std::vector<std::string> args = {grid.string(), (dir / name).string()};
    if (name[0] == 'r') args.push_back("--raw");
    ASSERT_EQ(run_tool("ctsurg-surface", args).exit_code, 0) << name;
    EXPECT_EQ(degenerate_gltf(dir / name, kCellMm), "") << name;
  }
  EXPECT_TRUE(ctsurg::test::gltf_validates({dir / "s.glb", dir / "r.glb", dir / "s.gltf"}));
}

TEST(CtsurgSurface, ExportsGlbStlObjPly) {
  TempDir dir;
  const fs::path grid = write_surface_grid(dir, "g.h5");
  for (const std::string name : {"s.glb", "s.stl", "s.obj", "s.ply", "s.gltf"}) {
    const auto r = run_tool("ctsurg-surface", {grid.string(), (dir / name).string()});
    ASSERT_EQ(r.exit_code, 0) << name << ": " << r.output;
    ASSERT_GT(fs::file_size(dir / name), 1000u) << name;
  }
  EXPECT_EQ(read_bytes(dir / "s.glb").substr(0, 4), "glTF");
  EXPECT_EQ(degenerate_gltf(dir / "s.glb", kCellMm), "");
  EXPECT_EQ(degenerate_gltf(dir / "s.gltf", kCellMm), "");
  EXPECT_TRUE(fs::exists(dir / "s.bin"));
  EXPECT_NE(read_bytes(dir / "s.gltf").find("\"s.bin\""), std::string::npos);
  EXPECT_FALSE(fs::exists(dir / "s.mtl"));
  EXPECT_TRUE(ctsurg::test::gltf_validates({dir / "s.glb", dir / "s.gltf"}));
  for (const std::string name : {"s.glb", "s.gltf"}) {
    const auto j = ctsurg::test::read_gltf(dir / name).json;
    EXPECT_FALSE(j.contains("extensionsUsed")) << name << ": " << j.dump();
    EXPECT_FALSE(j.contains("extensionsRequired")) << name;
    EXPECT_EQ(j.dump().find("\"extensions\""), std::string::npos) << name << ": " << j.dump();
    // The tissue material (gltf_material.h) even without a normal map; glTF's base colour is linear.
    const auto& m = j.at("materials").at(0);
    EXPECT_EQ(m.at("name"), "tissue") << name;
    const auto& base = m.at("pbrMetallicRoughness").at("baseColorFactor");
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(base.at(c).get<double>(), ctsurg::srgb_to_linear(ctsurg::kGltfTissueOnScreen[c]), 1e-6) << name;
    EXPECT_NEAR(m.at("pbrMetallicRoughness").at("roughnessFactor").get<double>(), ctsurg::kGltfTissueRoughness, 1e-6) << name;
  }
  const std::string stl = read_bytes(dir / "s.stl");
  ASSERT_GT(stl.size(), 84u);
  uint32_t facets = 0;
  std::memcpy(&facets, stl.data() + 80, 4);
  EXPECT_EQ(stl.size(), 84u + 50u * facets);
  for (const auto& f : ctsurg::test::files_in(dir.path())) EXPECT_EQ(f.filename().string().rfind(".tmp-", 0), std::string::npos) << f;
}

// glTF is metres with +X the patient's left, +Y superior, +Z anterior (docs/formats.md): a box of
// HU 300 in air at a known LPS place, of a different size along each axis (20, 10, 5 voxels of 1 mm),
// lands with POSITION min/max on the rotated, scaled box. The iso -350 is halfway between the two
// HU values, so each face is half a voxel outside the centres of the box's outer voxels (--raw:
// smoothing would round the box's edges).
TEST(CtsurgSurface, GltfIsInMetresWithSuperiorUpAndAnteriorToTheFront) {
  TempDir dir;
  ctsurg::HuVolume v;
  ctsurg::ImageGeometry g;
  g.dims = {30, 20, 14};
  g.origin = Eigen::Vector3d(-40.0, 10.0, 200.0);
  v.hu = ctsurg::Volume<float>(g, -1000.0f);
  for (int64_t k = 4; k < 9; ++k)
    for (int64_t j = 4; j < 14; ++j)
      for (int64_t i = 4; i < 24; ++i) v.hu(i, j, k) = 300.0f;
  ctsurg::write_hu_volume_file(dir / "ct.h5", v, test_provenance());
  // LPS extent, mm: x [-36.5, -16.5] (left), y [13.5, 23.5] (posterior), z [203.5, 208.5] (superior).
  const double lo_lps[3] = {-36.5, 13.5, 203.5}, hi_lps[3] = {-16.5, 23.5, 208.5};
  // glTF, m: X = x, Y = z, Z = -y.
  const double lo[3] = {lo_lps[0] / 1000, lo_lps[2] / 1000, -hi_lps[1] / 1000};
  const double hi[3] = {hi_lps[0] / 1000, hi_lps[2] / 1000, -lo_lps[1] / 1000};
  for (const std::string name : {"box.glb", "box.gltf"}) {
    const auto r = run_tool("ctsurg-surface", {(dir / "ct.h5").string(), (dir / name).string(), "--iso", "-350", "--raw"});
    ASSERT_EQ(r.exit_code, 0) << name << ": " << r.output;
    const auto gltf = ctsurg::test::read_gltf(dir / name);
    const auto& position = gltf.json.at("accessors").at(gltf.attribute("POSITION"));
    const std::vector<float> p = gltf.floats(gltf.attribute("POSITION"));
    ASSERT_FALSE(p.empty()) << name;
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(position.at("min").at(a).get<double>(), lo[a], 1e-6) << name << " axis " << a;
      EXPECT_NEAR(position.at("max").at(a).get<double>(), hi[a], 1e-6) << name << " axis " << a;
      float mn = p[a], mx = p[a];
      for (std::size_t i = a; i < p.size(); i += 3) mn = std::min(mn, p[i]), mx = std::max(mx, p[i]);
      EXPECT_NEAR(mn, lo[a], 1e-6) << name << " axis " << a;
      EXPECT_NEAR(mx, hi[a], 1e-6) << name << " axis " << a;
    }
  }
  EXPECT_TRUE(ctsurg::test::gltf_validates({dir / "box.glb", dir / "box.gltf"}));
}

// After the rotation to glTF's axes the ball still faces outward: every vertex normal and every
// triangle's counter-clockwise face normal point away from the ball's centre (rotated and scaled the
// same way), and the normals are unit.
TEST(CtsurgSurface, GltfNormalsAndWindingFaceOutward) {
  TempDir dir;
  const fs::path grid = write_surface_grid(dir, "g.h5");
  for (const std::string name : {"s.glb", "s.gltf"}) {
    ASSERT_EQ(run_tool("ctsurg-surface", {grid.string(), (dir / name).string()}).exit_code, 0) << name;
  }
  // write_surface_grid's centre, LPS mm: origin + 2 mm * (8.4, 8.1, 7.6); in glTF metres (x, z, -y) / 1000.
  const Eigen::Vector3d lps(-17.0 + 16.8, -16.0 + 16.2, 85.0 + 15.2);
  const Eigen::Vector3d centre = Eigen::Vector3d(lps.x(), lps.z(), -lps.y()) / 1000.0;
  for (const std::string name : {"s.glb", "s.gltf"}) {
    const auto gltf = ctsurg::test::read_gltf(dir / name);
    const std::vector<float> p = gltf.floats(gltf.attribute("POSITION")), n = gltf.floats(gltf.attribute("NORMAL"));
    const std::vector<uint32_t> tri =
        gltf.indices(gltf.json.at("meshes").at(0).at("primitives").at(0).at("indices").get<std::size_t>());
    ASSERT_EQ(p.size(), n.size()) << name;
    ASSERT_GT(tri.size(), 1500u) << name;
    const auto at = [](const std::vector<float>& a, std::size_t v) {
      return Eigen::Vector3d(a[3 * v], a[3 * v + 1], a[3 * v + 2]);
    };
    int inward_normals = 0, inward_faces = 0;
    for (std::size_t v = 0; v < p.size() / 3; ++v) {
      EXPECT_NEAR(at(n, v).norm(), 1.0, 1e-4) << name << " vertex " << v;
      // Within 1 mm of the 12 mm sphere: metres.
      EXPECT_NEAR((at(p, v) - centre).norm(), kSurfaceRadiusMm / 1000.0, 1e-3) << name << " vertex " << v;
      inward_normals += at(n, v).dot(at(p, v) - centre) <= 0.0;
    }
    for (std::size_t f = 0; f + 2 < tri.size(); f += 3) {
      const Eigen::Vector3d a = at(p, tri[f]), b = at(p, tri[f + 1]), c = at(p, tri[f + 2]);
      inward_faces += (b - a).cross(c - a).dot((a + b + c) / 3.0 - centre) <= 0.0;
    }
    EXPECT_EQ(inward_normals, 0) << name;
    EXPECT_EQ(inward_faces, 0) << name;
  }
}

// .vtk and .vtp for 3D Slicer: the SPACE=LPS marker, normals as point data, read back by VTK when
// python3-vtk9 is installed.
TEST(CtsurgSurface, ExportsVtkAndVtpWithTheLpsMarker) {
  TempDir dir;
  const fs::path grid = write_surface_grid(dir, "g.h5");
  ASSERT_EQ(run_tool("ctsurg-surface", {grid.string(), (dir / "s.h5").string()}).exit_code, 0);
  const auto mesh = ctsurg::read_surface_mesh_file(dir / "s.h5");
  for (const std::string name : {"s.vtk", "s.vtp"}) {
    const auto r = run_tool("ctsurg-surface", {grid.string(), (dir / name).string()});
    ASSERT_EQ(r.exit_code, 0) << name << "\n" << r.output;
  }
  std::ifstream vtk(dir / "s.vtk");
  std::string l1, l2;
  std::getline(vtk, l1);
  std::getline(vtk, l2);
  EXPECT_EQ(l1, "# vtk DataFile Version 4.2");
  EXPECT_NE(l2.find("SPACE=LPS"), std::string::npos) << l2;
  const std::string vtp = ctsurg::test::read_bytes(dir / "s.vtp");
  EXPECT_NE(vtp.find("Name=\"SPACE\""), std::string::npos);
  EXPECT_NE(vtp.find("Name=\"Normals\""), std::string::npos);
  const std::string python = ctsurg::test::python_with_vtk();
  if (python.empty()) GTEST_SKIP() << "python3-vtk9 absent";
  const std::string script =
      "import vtk\n"
      "a = vtk.vtkPolyDataReader(); a.SetFileName('" + (dir / "s.vtk").string() + "'); a.Update()\n"
      "b = vtk.vtkXMLPolyDataReader(); b.SetFileName('" + (dir / "s.vtp").string() + "'); b.Update()\n"
      "for r in (a, b):\n"
      "  g = r.GetOutput(); n = g.GetPointData().GetNormals()\n"
      "  print('MESH', g.GetNumberOfPoints(), g.GetNumberOfPolys(), n.GetNumberOfTuples(), g.GetPoint(0)[2])\n"
      "print('HEADER', a.GetHeader())\n"
      "print('SPACE', b.GetOutput().GetFieldData().GetAbstractArray('SPACE').GetValue(0))\n";
  const fs::path py = dir / "check.py";
  std::ofstream(py) << script;
  const auto r = ctsurg::test::run_shell(python + " " + py.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string expect = fmt::format("MESH {} {} {}", mesh.vertex_count(), mesh.triangle_count(), mesh.vertex_count());
  std::size_t first = r.output.find(expect);
  ASSERT_NE(first, std::string::npos) << r.output;
  EXPECT_NE(r.output.find(expect, first + 1), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("SPACE=LPS"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("SPACE LPS"), std::string::npos) << r.output;
}

TEST(CtsurgSurface, RerunIsByteIdentical) {
  TempDir dir;
  const fs::path grid = write_surface_grid(dir, "g.h5");
  const std::vector<std::string> args = {grid.string(), (dir / "s.h5").string(), "--threads", "1"};
  ASSERT_EQ(run_tool("ctsurg-surface", args).exit_code, 0);
  const std::string h5 = read_bytes(dir / "s.h5"), xdmf = read_bytes(dir / "s.xdmf");
  // Another thread count gives the same mesh (only the recorded command line differs).
  ASSERT_EQ(run_tool("ctsurg-surface", {grid.string(), (dir / "t.h5").string(), "--threads", "2"}).exit_code, 0);
  const auto a = ctsurg::read_surface_mesh_file(dir / "s.h5"), b = ctsurg::read_surface_mesh_file(dir / "t.h5");
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_EQ(a.triangles, b.triangles);
  EXPECT_EQ(a.normals, b.normals);  // smoothed, volume restored, cleaned, tied: all thread-independent
  EXPECT_EQ(a.grid_weights, b.grid_weights);
  ASSERT_EQ(run_tool("ctsurg-surface", args).exit_code, 0);
  EXPECT_TRUE(read_bytes(dir / "s.h5") == h5);
  EXPECT_TRUE(read_bytes(dir / "s.xdmf") == xdmf);
}

TEST(CtsurgSurface, HuVolumeNeedsIso) {
  TempDir dir;
  write_block_ct(dir, false);
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

TEST(CtsurgSurface, ClosesTheSurfaceAtTheLatticeBorderUnlessAskedNotTo) {
  TempDir dir;
  const fs::path ct = write_block_ct(dir, true);
  const auto closed = run_tool("ctsurg-surface", {ct.string(), (dir / "c.h5").string(), "--iso", "150"});
  ASSERT_EQ(closed.exit_code, 0) << closed.output;
  EXPECT_NE(closed.output.find("closing the surface"), std::string::npos) << closed.output;
  const auto c = ctsurg::read_surface_mesh_file(dir / "c.h5");
  EXPECT_TRUE(closed_and_oriented(c));
  EXPECT_EQ(c.lattice.dims[0], 14);  // the one-node frame
  // The block reaches past its border nodes towards the frame: more than the 5^3 mm of a block
  // whose surface stops at its outermost nodes.
  EXPECT_GT(enclosed_volume(c), 5.0 * 5.0 * 5.5);
  const auto open = run_tool("ctsurg-surface", {ct.string(), (dir / "o.h5").string(), "--iso", "150", "--open-border"});
  ASSERT_EQ(open.exit_code, 0) << open.output;
  EXPECT_NE(open.output.find("open there"), std::string::npos) << open.output;
  const auto o = ctsurg::read_surface_mesh_file(dir / "o.h5");
  EXPECT_FALSE(closed_and_oriented(o));
  EXPECT_EQ(o.lattice.dims[0], 12);
}

// --smooth and --decimate: still closed, fewer triangles, the ball's volume, and the lattice tie
// recomputed so that the weights reproduce the moved vertices.
TEST(CtsurgSurface, SmoothedAndDecimatedSurfaceStaysClosedAndTied) {
  TempDir dir;
  const fs::path grid = write_surface_grid(dir, "g.h5");
  ASSERT_EQ(run_tool("ctsurg-surface", {grid.string(), (dir / "full.h5").string()}).exit_code, 0);
  const auto r = run_tool("ctsurg-surface", {grid.string(), (dir / "s.h5").string(), "--smooth", "10", "--decimate", "400"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto full = ctsurg::read_surface_mesh_file(dir / "full.h5");
  const auto m = ctsurg::read_surface_mesh_file(dir / "s.h5");
  EXPECT_TRUE(closed_and_oriented(m));
  EXPECT_EQ(degenerate(m), "");
  EXPECT_LE(m.triangle_count(), 402);
  EXPECT_LT(m.triangle_count(), full.triangle_count() / 2);
  const double ball = 4.0 / 3.0 * std::numbers::pi * std::pow(kSurfaceRadiusMm, 3);
  EXPECT_NEAR(enclosed_volume(m), ball, 0.05 * ball);
  ASSERT_EQ(m.grid_weights.size(), 8 * static_cast<std::size_t>(m.vertex_count()));
  for (int64_t v = 0; v < m.vertex_count(); ++v) {
    const auto i = static_cast<std::size_t>(v);
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (int c = 0; c < 8; ++c)
      p += double(m.grid_weights[8 * i + static_cast<std::size_t>(c)]) *
           m.lattice.index_to_world(Eigen::Vector3d(m.grid_cell[3 * i] + (c & 1), m.grid_cell[3 * i + 1] + ((c >> 1) & 1),
                                                    m.grid_cell[3 * i + 2] + ((c >> 2) & 1)));
    ASSERT_LT((p - ctsurg::test::vertex(m, static_cast<uint32_t>(v))).norm(), 1e-3) << "vertex " << v;
  }
}

TEST(CtsurgSurface, BadInputExitsTwoAndLeavesNoFile) {
  TempDir dir;
  const fs::path grid = write_surface_grid(dir, "g.h5");
  const fs::path empty = write_surface_grid(dir, "empty.h5", true);
  const auto expect_bad = [&](const std::vector<std::string>& args, const std::string& says) {
    const auto before = ctsurg::test::files_in(dir.path());
    const auto r = run_tool("ctsurg-surface", args);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(says), std::string::npos) << r.output;
    EXPECT_EQ(ctsurg::test::files_in(dir.path()), before) << r.output;
  };
  expect_bad({empty.string(), (dir / "s.h5").string()}, "no surface at iso 0.5");
  expect_bad({grid.string(), (dir / "s.wrl").string()}, "unknown output format");
  expect_bad({(dir / "missing.h5").string(), (dir / "s.h5").string()}, "missing.h5");
  expect_bad({grid.string(), (dir / "no_such_folder" / "s.h5").string()}, "no_such_folder");
  expect_bad({grid.string(), (dir / "s.h5").string(), "--iso", "nan"}, "--iso");
  expect_bad({grid.string(), (dir / "s.h5").string(), "--decimate", "2"}, "--decimate");
  expect_bad({grid.string(), (dir / "s.h5").string(), "--smooth", "-1"}, "--smooth");
  expect_bad({grid.string(), (dir / "s.h5").string(), "--smooth", "1001"}, "--smooth");
  expect_bad({grid.string(), (dir / "s.h5").string(), "--smooth-method", "laplace"}, "--smooth-method");
  expect_bad({grid.string(), (dir / "s.h5").string(), "--pass-band", "2"}, "--pass-band");
  expect_bad({grid.string(), (dir / "s.h5").string(), "--pass-band", "0"}, "--pass-band");
  expect_bad({grid.string(), (dir / "s.h5").string(), "--raw", "--smooth", "5"}, "--raw");
  expect_bad({grid.string(), (dir / "s.h5").string(), "--raw", "--smooth-method", "taubin"}, "--raw");
  // Issue 17: --threads 1000000 crashed; an output that is the input replaced it.
  expect_bad({grid.string(), (dir / "s.h5").string(), "--threads", "1000000"}, "--threads");
  expect_bad({grid.string(), grid.string()}, "is the input");
}

// Issue 17: NaN in a CT gave NaN surface vertices. A volume that holds NaN (written by another
// program) is refused where it enters, naming the voxel.
TEST(CtsurgSurface, ANanVoxelIsRefusedWhereItEnters) {
  TempDir dir;
  ctsurg::HuVolume v;
  ctsurg::ImageGeometry g;
  g.dims = {12, 12, 12};
  v.hu = ctsurg::Volume<float>(g, -1000.5f);  // fractional: stored as float32, where NaN can be
  for (int64_t k = 3; k < 9; ++k)
    for (int64_t j = 3; j < 9; ++j)
      for (int64_t i = 3; i < 9; ++i) v.hu(i, j, k) = 300.0f;
  const fs::path ct = dir / "ct.h5";
  ctsurg::write_hu_volume_file(ct, v, test_provenance());
  {
    const hid_t file = H5Fopen(ct.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    const hid_t ds = H5Dopen2(file, "/hu/data", H5P_DEFAULT);
    const hid_t space = H5Dget_space(ds);
    std::vector<float> values(static_cast<std::size_t>(H5Sget_simple_extent_npoints(space)));
    ASSERT_GE(H5Dread(ds, H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), 0);
    values[values.size() / 2] = std::nanf("");
    ASSERT_GE(H5Dwrite(ds, H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), 0);
    H5Sclose(space);
    H5Dclose(ds);
    H5Fclose(file);
  }
  const auto r = run_tool("ctsurg-surface", {ct.string(), (dir / "s.h5").string(), "--iso", "0"});
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("/hu/data: NaN at voxel"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "s.h5"));
}

// Issue 17: on a full disk, .stl/.obj/.ply surfaces were committed truncated with exit 0, replacing
// the previous file (Assimp's file I/O drops write errors). Here a 4 KiB file-size limit.
TEST(CtsurgSurface, AFullDiskKeepsThePreviousMeshFile) {
  TempDir dir;
  const fs::path grid = write_surface_grid(dir, "g.h5");
  for (const char* name : {"s.stl", "s.obj", "s.ply", "s.glb", "s.gltf"}) {
    std::ofstream(dir / name) << "previous";
    const auto r = ctsurg::test::run_shell("trap '' XFSZ; ulimit -f 4; CTSURG_NO_PROGRESS=1 " + std::string(CTSURG_TOOL_DIR) +
                                           "/ctsurg-surface " + grid.string() + " " + (dir / name).string());
    EXPECT_EQ(r.exit_code, 1) << name << ": " << r.output;
    EXPECT_EQ(ctsurg::test::read_bytes(dir / name), "previous") << name;
  }
  EXPECT_EQ(ctsurg::test::files_in(dir.path()).size(), 7u) << "temporary files left behind";  // + g.h5, g.xdmf
}

}  // namespace
