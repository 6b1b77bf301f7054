// Tests for core/include/ctsurg/core/tet_mesh_file.h: round trip of every array and attribute, the
// XDMF sidecar, and validation errors on write and read.
#include "ctsurg/core/tet_mesh_file.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/hdf5_file.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;
using ctsurg::test::TempDir;

namespace {

using ctsurg::test::test_provenance;

// Two tets sharing face (1, 2, 3): label 1 below, label 2 above; six boundary faces.
ctsurg::TetMesh two_tets() {
  ctsurg::TetMesh m;
  m.nodes = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
  m.tets = {0, 1, 2, 3, 4, 1, 3, 2};
  m.tet_labels = {1, 2};
  m.boundary_faces = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3, 4, 3, 1, 4, 2, 3, 4, 1, 2};
  m.face_labels = {1, 0, 1, 0, 1, 0, 1, 2, 2, 0, 2, 0, 2, 0};
  m.quality.min_dihedral_deg = 54.7;
  m.quality.max_dihedral_deg = 90.0;
  m.quality.min_radius_edge = 0.8;
  m.quality.mean_radius_edge = 0.85;
  m.quality.max_radius_edge = 0.9;
  m.quality.slivers = 0;
  m.quality.inverted = 0;
  m.quality.volume_mm3 = 0.5;
  m.quality.radius_edge_bin_edges = {0.6, 0.7, 0.8};
  m.quality.radius_edge_histogram = {0, 2};
  m.mask_volume_mm3 = 0.48;
  m.seed = 42;
  m.criteria = R"({"cell_size_mm":2.4})";
  return m;
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(TetMeshFile, RoundTrip) {
  TempDir dir;
  const auto m = two_tets();
  ctsurg::write_tet_mesh_file(dir / "m.h5", m, test_provenance());
  const auto r = ctsurg::read_tet_mesh_file(dir / "m.h5");
  EXPECT_EQ(r.nodes, m.nodes);
  EXPECT_EQ(r.tets, m.tets);
  EXPECT_EQ(r.tet_labels, m.tet_labels);
  EXPECT_EQ(r.boundary_faces, m.boundary_faces);
  EXPECT_EQ(r.face_labels, m.face_labels);
  EXPECT_DOUBLE_EQ(r.quality.min_dihedral_deg, 54.7);
  EXPECT_DOUBLE_EQ(r.quality.max_dihedral_deg, 90.0);
  EXPECT_DOUBLE_EQ(r.quality.mean_radius_edge, 0.85);
  EXPECT_DOUBLE_EQ(r.quality.volume_mm3, 0.5);
  EXPECT_EQ(r.quality.radius_edge_bin_edges, m.quality.radius_edge_bin_edges);
  EXPECT_EQ(r.quality.radius_edge_histogram, m.quality.radius_edge_histogram);
  EXPECT_DOUBLE_EQ(r.mask_volume_mm3, 0.48);
  EXPECT_EQ(r.seed, 42u);
  EXPECT_EQ(r.criteria, m.criteria);
  const std::string xdmf = read_text(dir / "m.xdmf");
  EXPECT_NE(xdmf.find("TopologyType=\"Tetrahedron\" NumberOfElements=\"2\""), std::string::npos) << xdmf;
  EXPECT_NE(xdmf.find("m.h5:/tetmesh/nodes"), std::string::npos);
  EXPECT_NE(xdmf.find("m.h5:/tetmesh/tet_labels"), std::string::npos);
  const auto f = ctsurg::h5::File::open(dir / "m.h5");
  EXPECT_EQ(f.root().string_attribute("ctsurg_format"), "tet_mesh");
  EXPECT_EQ(f.root().open_group("tetmesh").ints_attribute("labels"), (std::vector<int64_t>{1, 2}));
}

TEST(TetMeshFile, WriteRejectsInconsistentMeshesAndLeavesNoFile) {
  TempDir dir;
  const auto expect_bad = [&](ctsurg::TetMesh m, const std::string& says) {
    try {
      ctsurg::write_tet_mesh_file(dir / "bad.h5", m, test_provenance());
      ADD_FAILURE() << "no error for " << says;
    } catch (const ctsurg::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(dir / "bad.h5"));
    EXPECT_FALSE(fs::exists(dir / "bad.xdmf"));
  };
  auto m = two_tets();
  m.tets[5] = 5;
  expect_bad(m, "node index 5 out of range");
  m = two_tets();
  m.boundary_faces[0] = -1;
  expect_bad(m, "/tetmesh/boundary_faces");
  m = two_tets();
  m.tet_labels.pop_back();
  expect_bad(m, "one label per tet");
  m = two_tets();
  m.face_labels.pop_back();
  expect_bad(m, "two labels per boundary face");
  m = two_tets();
  m.tets.clear();
  m.tet_labels.clear();
  expect_bad(m, "empty");
  m = two_tets();
  m.nodes.pop_back();
  expect_bad(m, "multiple");
  m = two_tets();
  m.quality.radius_edge_histogram.push_back(1);
  expect_bad(m, "histogram");
}

TEST(TetMeshFile, ReadRejectsOtherFilesAndBadShapes) {
  TempDir dir;
  {
    auto f = ctsurg::h5::File::create(dir / "other.h5");
    f.root().set_attribute("ctsurg_format", std::string("surface_mesh"));
    f.close();
  }
  EXPECT_THROW(ctsurg::read_tet_mesh_file(dir / "other.h5"), ctsurg::InputError);
  EXPECT_THROW(ctsurg::read_tet_mesh_file(dir / "missing.h5"), ctsurg::InputError);
  // A file whose tets have three columns.
  ctsurg::write_tet_mesh_file(dir / "m.h5", two_tets(), test_provenance());
  {
    auto f = ctsurg::h5::File::create(dir / "bad.h5");
    auto root = f.root();
    root.set_attribute("ctsurg_format", std::string("tet_mesh"));
    auto g = root.create_group("tetmesh");
    const std::vector<double> nodes{0, 0, 0, 1, 0, 0, 0, 1, 0};
    const std::vector<int32_t> tets{0, 1, 2};
    const std::array<uint64_t, 2> n3{3, 3}, t3{1, 3};
    g.write_dataset("nodes", nodes, n3);
    g.write_dataset("tets", tets, t3);
    f.close();
  }
  try {
    ctsurg::read_tet_mesh_file(dir / "bad.h5");
    ADD_FAILURE() << "no error";
  } catch (const ctsurg::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/tetmesh/tets"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("bad.h5"), std::string::npos) << e.what();
  }
}

}  // namespace

// Issue 17: NaN never crosses a stage boundary: a tet mesh with a non-finite node is not written.
TEST(TetMeshFile, NonFiniteNodesAreRefused) {
  TempDir dir;
  ctsurg::TetMesh m = two_tets();
  m.nodes[4] = std::nan("");
  try {
    ctsurg::write_tet_mesh_file(dir / "m.h5", m, test_provenance());
    ADD_FAILURE() << "a NaN node was written";
  } catch (const ctsurg::InputError& e) {
    EXPECT_EQ(e.field(), "/tetmesh/nodes");
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "m.h5"));
}
