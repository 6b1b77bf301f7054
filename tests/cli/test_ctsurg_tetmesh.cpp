// ctsurg-tetmesh as a user runs it: an occupancy grid of a ball (full-resolution mask and grid
// labels) written with write_occupancy_grid_file, then the tool's .h5 / .vtu / .msh / .mesh outputs,
// uniform refinement (--refine), byte-identical reruns and bad-input handling (exit 2, a message naming the problem, no file left).
#include "ctsurg/core/occupancy_grid_file.h"
#include "ctsurg/core/provenance.h"
#include "ctsurg/core/tet_mesh_file.h"
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

constexpr double kTetRadiusMm = 8.0;

using ctsurg::test::test_provenance;

// A ball of radius 8 mm: the mask on 1 mm voxels, the grid on 2 mm cells; `empty` gives no tissue.
fs::path write_tet_grid(const TempDir& dir, const std::string& name, bool empty = false) {
  ctsurg::ImageGeometry mg;
  mg.dims = {22, 21, 20};
  mg.origin = Eigen::Vector3d(-17.0, -16.0, 85.0);
  const Eigen::Vector3d centre = mg.index_to_world(Eigen::Vector3d(10.5, 10.0, 9.5));
  ctsurg::ImageGeometry gg = mg;
  gg.dims = {11, 11, 10};
  gg.spacing = Eigen::Vector3d::Constant(2.0);
  gg.origin = mg.origin + Eigen::Vector3d::Constant(0.5);
  ctsurg::OccupancyGrid grid;
  grid.mask = ctsurg::Volume<uint16_t>(mg, 0);
  grid.fraction = ctsurg::Volume<float>(gg, 0.0f);
  grid.occupancy = ctsurg::Volume<uint8_t>(gg, 0);
  grid.label = ctsurg::Volume<uint16_t>(gg, 0);
  for (int64_t k = 0; k < mg.dims[2] && !empty; ++k)
    for (int64_t j = 0; j < mg.dims[1]; ++j)
      for (int64_t i = 0; i < mg.dims[0]; ++i)
        grid.mask(i, j, k) = (mg.index_to_world(Eigen::Vector3d(double(i), double(j), double(k))) - centre).norm() <= kTetRadiusMm;
  for (int64_t k = 0; k < gg.dims[2] && !empty; ++k)
    for (int64_t j = 0; j < gg.dims[1]; ++j)
      for (int64_t i = 0; i < gg.dims[0]; ++i) {
        const bool in = (gg.index_to_world(Eigen::Vector3d(double(i), double(j), double(k))) - centre).norm() <= kTetRadiusMm;
        grid.fraction(i, j, k) = in ? 1.0f : 0.0f;
        grid.occupancy(i, j, k) = in;
        grid.label(i, j, k) = in;
      }
  grid.label_names = {{1, "ball"}};
  const fs::path p = dir / name;
  ctsurg::write_occupancy_grid_file(p, grid, test_provenance());
  return p;
}

using ctsurg::test::read_bytes;

const double kBall = 4.0 / 3.0 * std::numbers::pi * std::pow(kTetRadiusMm, 3);

TEST(CtsurgTetmesh, GridToTetMeshFileWithQualityReport) {
  TempDir dir;
  const fs::path grid = write_tet_grid(dir, "ball_grid.h5");
  const auto r = run_tool("ctsurg-tetmesh", {grid.string(), (dir / "ball.h5").string(), "--cell-size", "3", "--facet-size",
                                             "1.5", "--facet-distance", "0.3"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* says : {"tets expected", "dihedral angles", "slivers", "radius-edge histogram", "vs mask voxels"})
    EXPECT_NE(r.output.find(says), std::string::npos) << says << "\n" << r.output;
  ASSERT_TRUE(fs::exists(dir / "ball.xdmf"));
  EXPECT_NE(read_bytes(dir / "ball.xdmf").find("TopologyType=\"Tetrahedron\""), std::string::npos);
  const auto m = ctsurg::read_tet_mesh_file(dir / "ball.h5");
  EXPECT_GT(m.tet_count(), 300);
  EXPECT_EQ(m.quality.inverted, 0);
  EXPECT_EQ(m.quality.slivers, 0);
  EXPECT_NEAR(m.quality.volume_mm3, kBall, 0.05 * kBall);
  EXPECT_NEAR(m.mask_volume_mm3, kBall, 0.05 * kBall);
  EXPECT_NE(m.criteria.find("\"cell_size_mm\":3.0"), std::string::npos) << m.criteria;
  EXPECT_NE(m.criteria.find("\"facet_size_mm\":1.5"), std::string::npos) << m.criteria;

  // The coarse grid labels instead of the mask: a similar ball, fewer details.
  const auto g = run_tool("ctsurg-tetmesh", {grid.string(), (dir / "coarse.h5").string(), "--source", "grid"});
  ASSERT_EQ(g.exit_code, 0) << g.output;
  const auto c = ctsurg::read_tet_mesh_file(dir / "coarse.h5");
  EXPECT_EQ(c.quality.inverted, 0);
  EXPECT_NEAR(c.quality.volume_mm3, kBall, 0.25 * kBall);
  // Defaults: the cell size is the grid's (2 mm), the facet size the cell size, the facet distance
  // the larger of half a voxel and a quarter of the cell size.
  EXPECT_NE(c.criteria.find("\"cell_size_mm\":2.0"), std::string::npos) << c.criteria;
  EXPECT_NE(c.criteria.find("\"facet_size_mm\":2.0"), std::string::npos) << c.criteria;
  EXPECT_NE(c.criteria.find("\"facet_distance_mm\":1.0"), std::string::npos) << c.criteria;
}

TEST(CtsurgTetmesh, ExportsVtuMshMesh) {
  TempDir dir;
  const fs::path grid = write_tet_grid(dir, "g.h5");
  for (const std::string name : {"m.vtu", "m.msh", "m.mesh"}) {
    const auto r = run_tool("ctsurg-tetmesh", {grid.string(), (dir / name).string(), "--cell-size", "3"});
    ASSERT_EQ(r.exit_code, 0) << name << ": " << r.output;
    ASSERT_GT(fs::file_size(dir / name), 1000u) << name;
  }
  EXPECT_NE(read_bytes(dir / "m.vtu").find("<VTKFile type=\"UnstructuredGrid\""), std::string::npos);
  EXPECT_EQ(read_bytes(dir / "m.msh").substr(0, 24), "$MeshFormat\n4.1 0 8\n$End");
  EXPECT_EQ(read_bytes(dir / "m.mesh").substr(0, 22), "MeshVersionFormatted 2");
  for (const auto& f : ctsurg::test::files_in(dir.path())) EXPECT_EQ(f.filename().string().rfind(".tmp-", 0), std::string::npos) << f;
}

// --import: a mesh from another mesher (here a Gmsh 2.2 file with one inverted tet) becomes a ctsurg
// tet mesh file with boundary faces and quality; a bad file is exit 2 naming the element.
TEST(CtsurgTetmesh, ImportsAnotherMeshersFile) {
  TempDir dir;
  std::ofstream(dir / "two.msh") << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n5\n1 0 0 0\n2 10 0 0\n3 0 10 0\n"
                                    "4 0 0 10\n5 10 10 10\n$EndNodes\n$Elements\n2\n1 4 2 2 1 1 2 3 4\n"
                                    "2 4 2 3 1 5 2 3 4\n$EndElements\n";
  const auto r = run_tool("ctsurg-tetmesh", {"--import", (dir / "two.msh").string(), (dir / "two.h5").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("1 of 2 tets were negatively oriented; flipped"), std::string::npos) << r.output;
  const auto m = ctsurg::read_tet_mesh_file(dir / "two.h5");
  EXPECT_EQ(m.tet_count(), 2);
  EXPECT_EQ(m.tet_labels, (std::vector<uint16_t>{2, 3}));
  EXPECT_EQ(m.boundary_face_count(), 7);  // 6 skin faces and the interface
  EXPECT_EQ(m.quality.inverted, 0);
  const auto vtu = run_tool("ctsurg-tetmesh", {"--import", (dir / "two.msh").string(), (dir / "two.vtu").string()});
  ASSERT_EQ(vtu.exit_code, 0) << vtu.output;
  EXPECT_NE(ctsurg::test::read_bytes(dir / "two.vtu").find("Name=\"labels\""), std::string::npos);

  std::ofstream(dir / "bad.mesh") << "MeshVersionFormatted 2\nDimension 3\nVertices\n4\n0 0 0 0\n1 0 0 0\n0 1 0 0\n"
                                     "0 0 1 0\nTetrahedra\n1\n1 2 3 7 1\nEnd\n";
  const auto before = ctsurg::test::files_in(dir.path());
  const auto bad = run_tool("ctsurg-tetmesh", {"--import", (dir / "bad.mesh").string(), (dir / "bad.h5").string()});
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("bad.mesh: tet 1: node index 7 out of range"), std::string::npos) << bad.output;
  const auto usage = run_tool("ctsurg-tetmesh", {"--import", (dir / "two.msh").string(), "g.h5", (dir / "x.h5").string()});
  EXPECT_EQ(usage.exit_code, 2) << usage.output;
  EXPECT_EQ(ctsurg::test::files_in(dir.path()), before);
}

// --refine: a mesh refined uniformly (every tet into eight), from the grid or from a ctsurg .h5 tet
// mesh; the same volume and skin, 8x the tets; too many tets refused before any is made.
TEST(CtsurgTetmesh, RefinesAMeshUniformly) {
  TempDir dir;
  const fs::path grid = write_tet_grid(dir, "g.h5");
  ASSERT_EQ(run_tool("ctsurg-tetmesh", {grid.string(), (dir / "coarse.h5").string(), "--cell-size", "3"}).exit_code, 0);
  const auto coarse = ctsurg::read_tet_mesh_file(dir / "coarse.h5");
  const auto r = run_tool("ctsurg-tetmesh", {"--import", (dir / "coarse.h5").string(), "--refine", "2", (dir / "fine.h5").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("refined 2 times"), std::string::npos) << r.output;
  const auto fine = ctsurg::read_tet_mesh_file(dir / "fine.h5");
  EXPECT_EQ(fine.tet_count(), 64 * coarse.tet_count());
  EXPECT_EQ(fine.boundary_face_count(), 16 * coarse.boundary_face_count());
  EXPECT_EQ(fine.quality.inverted, 0);
  EXPECT_NEAR(fine.quality.volume_mm3, coarse.quality.volume_mm3, 1e-9 * coarse.quality.volume_mm3);
  EXPECT_EQ(fine.mask_volume_mm3, coarse.mask_volume_mm3);
  EXPECT_NE(fine.criteria.find("\"refinements\":2"), std::string::npos) << fine.criteria;
  EXPECT_NE(fine.criteria.find("\"cell_size_mm\":3.0"), std::string::npos) << fine.criteria;
  // Straight from the grid: the same as meshing, then refining once.
  ASSERT_EQ(run_tool("ctsurg-tetmesh", {grid.string(), (dir / "direct.h5").string(), "--cell-size", "3", "--refine", "1"}).exit_code, 0);
  ASSERT_EQ(run_tool("ctsurg-tetmesh", {"--import", (dir / "coarse.h5").string(), "--refine", "1", (dir / "once.h5").string()}).exit_code, 0);
  const auto direct = ctsurg::read_tet_mesh_file(dir / "direct.h5"), once = ctsurg::read_tet_mesh_file(dir / "once.h5");
  EXPECT_EQ(direct.nodes, once.nodes);
  EXPECT_EQ(direct.tets, once.tets);
  // Refused, nothing written: out of range, or over --max-cells.
  const auto before = ctsurg::test::files_in(dir.path());
  const auto range = run_tool("ctsurg-tetmesh", {"--import", (dir / "coarse.h5").string(), "--refine", "5", (dir / "x.h5").string()});
  EXPECT_EQ(range.exit_code, 2) << range.output;
  EXPECT_NE(range.output.find("--refine"), std::string::npos) << range.output;
  const auto big = run_tool("ctsurg-tetmesh", {"--import", (dir / "coarse.h5").string(), "--refine", "3", "--max-cells", "1000",
                                               (dir / "x.h5").string()});
  EXPECT_EQ(big.exit_code, 2) << big.output;
  EXPECT_NE(big.output.find("over --max-cells 1000"), std::string::npos) << big.output;
  EXPECT_EQ(ctsurg::test::files_in(dir.path()), before);
}

TEST(CtsurgTetmesh, RerunIsByteIdentical) {
  TempDir dir;
  const fs::path grid = write_tet_grid(dir, "g.h5");
  const std::vector<std::string> args = {grid.string(), (dir / "s.h5").string(), "--cell-size", "3"};
  ASSERT_EQ(run_tool("ctsurg-tetmesh", args).exit_code, 0);
  const std::string h5 = read_bytes(dir / "s.h5"), xdmf = read_bytes(dir / "s.xdmf");
  ASSERT_EQ(run_tool("ctsurg-tetmesh", args).exit_code, 0);
  EXPECT_TRUE(read_bytes(dir / "s.h5") == h5);
  EXPECT_TRUE(read_bytes(dir / "s.xdmf") == xdmf);
  const std::vector<std::string> vtu = {grid.string(), (dir / "s.vtu").string(), "--cell-size", "3"};
  ASSERT_EQ(run_tool("ctsurg-tetmesh", vtu).exit_code, 0);
  const std::string first = read_bytes(dir / "s.vtu");
  ASSERT_EQ(run_tool("ctsurg-tetmesh", vtu).exit_code, 0);
  EXPECT_TRUE(read_bytes(dir / "s.vtu") == first);
}

TEST(CtsurgTetmesh, BadInputExitsTwoAndLeavesNoFile) {
  TempDir dir;
  const fs::path grid = write_tet_grid(dir, "g.h5");
  const fs::path empty = write_tet_grid(dir, "empty.h5", true);
  const auto expect_bad = [&](const std::vector<std::string>& args, const std::string& says) {
    const auto before = ctsurg::test::files_in(dir.path());
    const auto r = run_tool("ctsurg-tetmesh", args);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(says), std::string::npos) << r.output;
    EXPECT_EQ(ctsurg::test::files_in(dir.path()), before) << r.output;
  };
  const std::string out = (dir / "m.h5").string();
  expect_bad({empty.string(), out}, "nothing to mesh");
  expect_bad({grid.string(), out, "--labels", "5"}, "no voxel has label 5");
  expect_bad({grid.string(), out, "--labels", "1,x"}, "--labels");
  expect_bad({grid.string(), out, "--cell-size", "0"}, "--cell-size");
  expect_bad({grid.string(), out, "--cell-size", "-2"}, "--cell-size");
  expect_bad({grid.string(), out, "--facet-distance", "0"}, "--facet-distance");
  expect_bad({grid.string(), out, "--facet-angle", "40"}, "--facet-angle");
  expect_bad({grid.string(), out, "--radius-edge", "0.5"}, "--radius-edge");
  expect_bad({grid.string(), out, "--cell-size", "0.05", "--facet-size", "0.05"}, "--max-cells");
  expect_bad({grid.string(), out, "--max-cells", "50"}, "--max-cells");
  expect_bad({grid.string(), (dir / "m.vtk").string()}, "unknown output format");
  expect_bad({(dir / "missing.h5").string(), out}, "missing.h5");
  expect_bad({grid.string(), (dir / "no_such_folder" / "m.h5").string()}, "no_such_folder");
  // Issue 17: an output that is the input replaced it.
  expect_bad({grid.string(), grid.string()}, "is the input");
  // The memory guard: a fine mesh that cannot fit in the memory allowed is refused before meshing
  // (exit 1: out of memory, docs/formats.md).
  const auto before = ctsurg::test::files_in(dir.path());
  const auto r = ctsurg::test::run_shell("CTSURG_MAX_MEMORY_MB=200 " + std::string(CTSURG_TOOL_DIR) + "/ctsurg-tetmesh " +
                                         grid.string() + " " + out + " --cell-size 0.1 --facet-size 0.1 --max-cells 100000000");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("--cell-size 0.1"), std::string::npos) << r.output;
  EXPECT_EQ(ctsurg::test::files_in(dir.path()), before);
}

}  // namespace
