// Tests for mesh/include/ctsurg/mesh/tet_mesh_export.h: the VTU read back by VTK (python3-vtk9,
// skipped when absent), and the Gmsh .msh 4.1 and Medit .mesh files parsed section by section.
#include "ctsurg/mesh/tet_mesh_export.h"

#include "ctsurg/core/error.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

namespace fs = std::filesystem;
using ctsurg::test::TempDir;

namespace {

// Two tets sharing face (1, 2, 3): label 1 and label 2; six boundary faces (one per outer side).
ctsurg::TetMesh two_tets() {
  ctsurg::TetMesh m;
  m.nodes = {0.5, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1.25};
  m.tets = {0, 1, 2, 3, 4, 1, 3, 2};
  m.tet_labels = {1, 2};
  m.boundary_faces = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3, 4, 3, 1, 4, 2, 3, 4, 1, 2};
  m.face_labels = {1, 0, 1, 0, 1, 0, 1, 2, 2, 0, 2, 0, 2, 0};
  m.quality.radius_edge_bin_edges = {0.6, 0.7};
  m.quality.radius_edge_histogram = {2};
  return m;
}

std::vector<std::string> lines_of(const fs::path& p) {
  std::ifstream in(p);
  std::vector<std::string> out;
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

// The line after `header` in `lines`, or "" when there is none.
std::string after(const std::vector<std::string>& lines, const std::string& header) {
  for (std::size_t i = 0; i + 1 < lines.size(); ++i)
    if (lines[i] == header) return lines[i + 1];
  return "";
}

TEST(TetMeshExport, FormatBySuffix) {
  EXPECT_EQ(ctsurg::tet_mesh_export_format("a/b.vtu"), "vtu");
  EXPECT_EQ(ctsurg::tet_mesh_export_format("b.MSH"), "msh");
  EXPECT_EQ(ctsurg::tet_mesh_export_format("b.mesh"), "mesh");
  EXPECT_EQ(ctsurg::tet_mesh_export_format("b.vtk"), "");
  TempDir dir;
  EXPECT_THROW(ctsurg::export_tet_mesh(dir / "x.obj", two_tets()), ctsurg::InputError);
  auto bad = two_tets();
  bad.tets[0] = 9;
  EXPECT_THROW(ctsurg::export_tet_mesh(dir / "x.vtu", bad), ctsurg::InputError);
}

TEST(TetMeshExport, VtuReadsBackInVtk) {
  TempDir dir;
  // A temporary name with the format taken from format_of, as the tool writes it.
  ctsurg::export_tet_mesh(dir / "tmp.part", two_tets(), "m.vtu");
  fs::rename(dir / "tmp.part", dir / "m.vtu");
  const std::string python = ctsurg::test::python_with_vtk();
  if (python.empty()) GTEST_SKIP() << "python3-vtk9 absent";
  const std::string script =
      "import vtk; r = vtk.vtkXMLUnstructuredGridReader(); r.SetFileName('" + (dir / "m.vtu").string() +
      "'); r.Update(); g = r.GetOutput(); l = g.GetCellData().GetArray('labels'); p = g.GetPoint(4); "
      "t = [g.GetPoint(g.GetCell(0).GetPointId(i)) for i in range(4)]; "
      "print('VTK', g.GetNumberOfPoints(), g.GetNumberOfCells(), g.GetCellType(0), g.GetCellType(1), "
      "l.GetValue(0), l.GetValue(1), p[0], p[1], p[2], round(vtk.vtkTetra.ComputeVolume(*t), 6))";
  const auto r = ctsurg::test::run_shell(python + " -c \"" + script + "\"");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // 5 points, 2 cells, VTK_TETRA = 10, labels 1 and 2, point 4 at (1, 1, 1.25), first tet's volume.
  EXPECT_NE(r.output.find("VTK 5 2 10 10 1 2 1.0 1.0 1.25"), std::string::npos) << r.output;
  // vtkTetra::ComputeVolume is signed: positive for our (positively oriented) tets. Tet 0 has
  // legs (0.5, 0, 0), (-0.5, 1, 0), (-0.5, 0, 1): volume 0.5 / 6.
  EXPECT_NE(r.output.find(" 0.083333"), std::string::npos) << r.output;
}

TEST(TetMeshExport, GmshMsh41Sections) {
  TempDir dir;
  ctsurg::export_tet_mesh(dir / "m.msh", two_tets());
  const auto l = lines_of(dir / "m.msh");
  EXPECT_EQ(after(l, "$MeshFormat"), "4.1 0 8");
  EXPECT_EQ(after(l, "$PhysicalNames"), "2");
  EXPECT_EQ(after(l, "$Entities"), "0 0 0 2");
  EXPECT_EQ(after(l, "$Nodes"), "1 5 1 5");
  EXPECT_EQ(after(l, "$Elements"), "2 2 1 2");
  // Element blocks: (dim 3, entity = label, type 4 = tet4, count), then "tag n1 n2 n3 n4" 1-based.
  EXPECT_EQ(after(l, "2 2 1 2"), "3 1 4 1");
  EXPECT_EQ(after(l, "3 1 4 1"), "1 1 2 3 4");
  EXPECT_EQ(after(l, "3 2 4 1"), "2 5 2 4 3");
  EXPECT_EQ(l.back(), "$EndElements");
  // Node coordinates follow the 5 tags.
  EXPECT_EQ(after(l, "5"), "0.5 0 0");
}

TEST(TetMeshExport, MeditMeshSections) {
  TempDir dir;
  ctsurg::export_tet_mesh(dir / "m.mesh", two_tets());
  const auto l = lines_of(dir / "m.mesh");
  EXPECT_EQ(l.at(0), "MeshVersionFormatted 2");
  EXPECT_EQ(after(l, "Dimension 3"), "Vertices");
  EXPECT_EQ(after(l, "Vertices"), "5");
  EXPECT_EQ(after(l, "Triangles"), "7");
  EXPECT_EQ(after(l, "Tetrahedra"), "2");
  EXPECT_EQ(after(l, "2"), "1 2 3 4 1");
  EXPECT_EQ(after(l, "1 2 3 4 1"), "5 2 4 3 2");
  EXPECT_EQ(after(l, "7"), "1 3 2 1");
  EXPECT_EQ(l.back(), "End");
}

}  // namespace
