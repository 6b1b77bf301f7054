// Tests for mesh/include/ctsurg/mesh/tet_mesh_import.h: export -> import round trips in .vtu, .msh
// (4.1 from ctsurg, 2.2 by hand) and .mesh; an inverted tet flipped and counted; boundary faces as
// the mesher's; bad files refused naming the file and element.
#include "ctsurg/mesh/tet_mesh_import.h"

#include "ctsurg/core/error.h"
#include "ctsurg/mesh/tet_mesh_export.h"
#include "ctsurg/mesh/tet_mesh_quality.h"
#include "test_support.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <fstream>
#include <set>

namespace fs = std::filesystem;
using ctsurg::test::TempDir;

namespace {

// A cube [0, 2]^3 split into 6 tets around the diagonal 0-6 (Kuhn), labels 3 (x < y) and 5; plus
// nodes on the cube corners. Positively oriented.
ctsurg::TetMesh cube() {
  ctsurg::TetMesh m;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) m.nodes.insert(m.nodes.end(), {2.0 * i - 10.0, 2.0 * j + 4.0, 2.0 * k + 100.5});
  // corner index = i + 2 j + 4 k; path 0 -> ... -> 7 along the three axes in each order
  const int paths[6][3] = {{1, 2, 4}, {1, 4, 2}, {2, 1, 4}, {2, 4, 1}, {4, 1, 2}, {4, 2, 1}};
  for (const auto& p : paths) {
    const int a = p[0], b = a + p[1], c = 7;
    std::array<int32_t, 4> t{0, a, b, c};
    const auto pt = [&](int v) {
      return Eigen::Vector3d(m.nodes[3 * v], m.nodes[3 * v + 1], m.nodes[3 * v + 2]);
    };
    if (ctsurg::tet_signed_volume(pt(t[0]), pt(t[1]), pt(t[2]), pt(t[3])) < 0) std::swap(t[2], t[3]);
    m.tets.insert(m.tets.end(), t.begin(), t.end());
    m.tet_labels.push_back(p[0] == 1 ? 3 : 5);
  }
  ctsurg::compute_boundary_faces(m);
  m.quality = ctsurg::tet_mesh_quality(m.nodes, m.tets);
  return m;
}

void write_text(const fs::path& p, const std::string& s) { std::ofstream(p, std::ios::binary) << s; }

std::string import_refusal(const fs::path& p) {
  try {
    ctsurg::import_tet_mesh(p);
  } catch (const ctsurg::InputError& e) {
    return e.what();
  }
  return "(imported)";
}

}  // namespace

TEST(TetMeshImport, BoundaryFacesAreOutwardAndSplitByLabel) {
  const ctsurg::TetMesh m = cube();
  // 12 skin triangles (2 per cube side) + the interface between labels 3 and 5.
  int64_t skin = 0, interface = 0;
  const Eigen::Vector3d centre(-9.0, 5.0, 101.5);
  for (int64_t f = 0; f < m.boundary_face_count(); ++f) {
    const auto p = [&](int c) {
      const int32_t v = m.boundary_faces[static_cast<std::size_t>(3 * f + c)];
      return Eigen::Vector3d(m.nodes[3 * v], m.nodes[3 * v + 1], m.nodes[3 * v + 2]);
    };
    const Eigen::Vector3d n = (p(1) - p(0)).cross(p(2) - p(0));
    const uint16_t in = m.face_labels[static_cast<std::size_t>(2 * f)], out = m.face_labels[static_cast<std::size_t>(2 * f + 1)];
    if (out == 0) {
      ++skin;
      EXPECT_GT(n.dot((p(0) + p(1) + p(2)) / 3.0 - centre), 0.0) << "skin face " << f << " points inwards";
    } else {
      ++interface;
      EXPECT_EQ(in, 3);
      EXPECT_EQ(out, 5);
    }
  }
  EXPECT_EQ(skin, 12);
  EXPECT_EQ(interface, 2);
  EXPECT_NEAR(m.quality.volume_mm3, 8.0, 1e-12);
}

TEST(TetMeshImport, RoundTripInEveryExportFormat) {
  TempDir dir;
  const ctsurg::TetMesh m = cube();
  for (const std::string ext : {".vtu", ".msh", ".mesh"}) {
    const fs::path p = dir / ("cube" + ext);
    ctsurg::export_tet_mesh(p, m);
    const ctsurg::TetMeshImport r = ctsurg::import_tet_mesh(p);
    EXPECT_EQ(r.flipped, 0) << ext;
    EXPECT_TRUE(r.labels_from_file) << ext;
    // Gmsh writes tets grouped by label: compare as sets of (nodes, label).
    EXPECT_EQ(r.mesh.nodes, m.nodes) << ext;
    std::set<std::pair<std::array<int32_t, 4>, uint16_t>> a, b;
    for (int64_t t = 0; t < m.tet_count(); ++t) {
      a.insert({{m.tets[4 * t], m.tets[4 * t + 1], m.tets[4 * t + 2], m.tets[4 * t + 3]}, m.tet_labels[t]});
      b.insert({{r.mesh.tets[4 * t], r.mesh.tets[4 * t + 1], r.mesh.tets[4 * t + 2], r.mesh.tets[4 * t + 3]},
                r.mesh.tet_labels[t]});
    }
    EXPECT_EQ(a, b) << ext;
    EXPECT_EQ(r.mesh.boundary_face_count(), m.boundary_face_count()) << ext;
    EXPECT_NEAR(r.mesh.quality.volume_mm3, 8.0, 1e-12) << ext;
  }
  // Medit files also hold the boundary triangles: read past, counted as skipped.
  EXPECT_EQ(ctsurg::import_tet_mesh(dir / "cube.mesh").skipped_cells, m.boundary_face_count());
}

TEST(TetMeshImport, Gmsh22WithAnInvertedTetIsFlippedAndCounted) {
  TempDir dir;
  // Node tags not 1..N, a triangle element skipped, tet 2 negatively oriented, unused node 50.
  write_text(dir / "two.msh",
             "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n6\n10 0 0 0\n11 1 0 0\n12 0 1 0\n13 0 0 1\n14 1 1 1\n"
             "50 9 9 9\n$EndNodes\n$Elements\n3\n1 2 2 7 1 10 11 12\n2 4 2 7 1 10 11 12 13\n3 4 2 8 2 14 11 12 13\n"
             "$EndElements\n");
  const ctsurg::TetMeshImport r = ctsurg::import_tet_mesh(dir / "two.msh");
  EXPECT_EQ(r.format, "msh 2.2");
  EXPECT_EQ(r.flipped, 1);
  EXPECT_EQ(r.unused_nodes, 1);
  EXPECT_EQ(r.skipped_cells, 1);
  EXPECT_EQ(r.mesh.node_count(), 5);
  EXPECT_EQ(r.mesh.tet_labels, (std::vector<uint16_t>{7, 8}));
  EXPECT_EQ(r.mesh.quality.inverted, 0);
  EXPECT_GT(r.mesh.quality.volume_mm3, 0.0);
}

TEST(TetMeshImport, BadFilesAreRefusedNamingFileAndElement) {
  TempDir dir;
  const std::string head = "MeshVersionFormatted 2\nDimension 3\nVertices\n5\n0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 1 0\n1 1 0 0\n";
  write_text(dir / "range.mesh", head + "Tetrahedra\n1\n1 2 3 9 1\nEnd\n");
  EXPECT_NE(import_refusal(dir / "range.mesh").find("range.mesh: tet 1: node index 9 out of range [1, 5]"), std::string::npos)
      << import_refusal(dir / "range.mesh");
  write_text(dir / "flat.mesh", head + "Tetrahedra\n2\n1 2 3 4 1\n1 2 3 5 1\nEnd\n");
  EXPECT_NE(import_refusal(dir / "flat.mesh").find("flat.mesh: tet 2: zero volume"), std::string::npos) << import_refusal(dir / "flat.mesh");
  write_text(dir / "dup.mesh", head + "Tetrahedra\n2\n1 2 3 4 1\n2 1 3 4 2\nEnd\n");
  EXPECT_NE(import_refusal(dir / "dup.mesh").find("dup.mesh: tet 2: the same four nodes as tet 1"), std::string::npos)
      << import_refusal(dir / "dup.mesh");
  // tests/fuzz_regressions/README.md: a Medit file declaring 935,854,226 vertices in 637 bytes had
  // 22 GB reserved for them; a count the rest of the file cannot hold is refused first.
  fs::copy_file(ctsurg::test::source_dir() / "tests" / "fuzz_regressions" / "fuzz_medit" / "oom-0bd670f2", dir / "oom.mesh");
  EXPECT_NE(import_refusal(dir / "oom.mesh").find("count 935854226 is more than the"), std::string::npos) << import_refusal(dir / "oom.mesh");
  write_text(dir / "label.mesh", head + "Tetrahedra\n1\n1 2 3 4 0\nEnd\n");
  EXPECT_NE(import_refusal(dir / "label.mesh").find("label 0 is not in [1, 65535]"), std::string::npos);
  write_text(dir / "short.mesh", head + "Tetrahedra\n2\n1 2 3 4 1\n");
  EXPECT_NE(import_refusal(dir / "short.mesh").find("short.mesh: Tetrahedra row 2: the file ends early"), std::string::npos)
      << import_refusal(dir / "short.mesh");
  write_text(dir / "bin.msh", "$MeshFormat\n4.1 1 8\n$EndMeshFormat\n");
  EXPECT_NE(import_refusal(dir / "bin.msh").find("binary MSH is not read"), std::string::npos);
  write_text(dir / "b.vtu",
             "<VTKFile type=\"UnstructuredGrid\"><UnstructuredGrid><Piece NumberOfPoints=\"1\" NumberOfCells=\"0\">"
             "<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"appended\" offset=\"0\"/></Points>"
             "</Piece></UnstructuredGrid></VTKFile>");
  EXPECT_NE(import_refusal(dir / "b.vtu").find("only ascii data arrays are read"), std::string::npos) << import_refusal(dir / "b.vtu");
  EXPECT_NE(import_refusal(dir / "x.obj").find("unknown tet mesh format"), std::string::npos);
}
