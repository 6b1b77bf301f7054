// The surface mesh file: a round trip with and without the optional atlas arrays and normal map
// (8 and 16 bits), and the checks on read and write.
#include <gtest/gtest.h>

#include <hdf5.h>

#include <cmath>

#include "ctsurg/core/error.h"
#include "ctsurg/core/surface_mesh_file.h"
#include "test_support.h"

namespace {

using ctsurg::test::test_provenance;

// One triangle split into a 4-vertex textured mesh (vertex 3 copies vertex 0).
ctsurg::SurfaceMesh textured(int bits) {
  ctsurg::SurfaceMesh m;
  m.vertices = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0};
  m.normals = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
  m.triangles = {0, 1, 2, 3, 2, 1};
  m.grid_cell = std::vector<int32_t>(12, 0);
  m.grid_weights = std::vector<float>(32, 0.125f);
  m.nearest_node = std::vector<int32_t>(12, 1);
  m.lattice.dims = {2, 2, 2};
  m.iso = 0.5;
  m.quantity = "fraction";
  m.source_dataset = "/grid/fraction";
  m.uvs = {0.1f, 0.9f, 0.9f, 0.9f, 0.1f, 0.1f, 0.5f, 0.5f};
  m.tangents = {1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, -1};
  m.source_vertex = {0, 1, 2, 0};
  m.source_vertex_count = 3;
  m.normal_map.width = 3;
  m.normal_map.height = 2;
  m.normal_map.bits = bits;
  for (int i = 0; i < 18; ++i) m.normal_map.rgb.push_back(static_cast<uint16_t>(bits == 8 ? 14 * i : 3000 * i));
  return m;
}

TEST(SurfaceMeshFile, OptionalAtlasAndNormalMapRoundTrip) {
  ctsurg::test::TempDir dir;
  for (const int bits : {8, 16}) {
    const ctsurg::SurfaceMesh m = textured(bits);
    ctsurg::write_surface_mesh_file(dir / "t.h5", m, test_provenance());
    const ctsurg::SurfaceMesh r = ctsurg::read_surface_mesh_file(dir / "t.h5");
    EXPECT_EQ(r.uvs, m.uvs);
    EXPECT_EQ(r.tangents, m.tangents);
    EXPECT_EQ(r.source_vertex, m.source_vertex);
    EXPECT_EQ(r.source_vertex_count, 3);
    EXPECT_EQ(r.normal_map.width, 3);
    EXPECT_EQ(r.normal_map.height, 2);
    EXPECT_EQ(r.normal_map.bits, bits);
    EXPECT_EQ(r.normal_map.rgb, m.normal_map.rgb);
  }
  // Without them: all empty after reading.
  ctsurg::SurfaceMesh plain = textured(8);
  plain.uvs.clear(), plain.tangents.clear(), plain.source_vertex.clear(), plain.normal_map = {};
  ctsurg::write_surface_mesh_file(dir / "p.h5", plain, test_provenance());
  const ctsurg::SurfaceMesh r = ctsurg::read_surface_mesh_file(dir / "p.h5");
  EXPECT_TRUE(r.uvs.empty() && r.tangents.empty() && r.source_vertex.empty() && r.normal_map.empty());
}

TEST(SurfaceMeshFile, RejectsInconsistentOptionalArrays) {
  ctsurg::test::TempDir dir;
  const auto bad = [&](auto change) {
    ctsurg::SurfaceMesh m = textured(8);
    change(m);
    EXPECT_THROW(ctsurg::write_surface_mesh_file(dir / "b.h5", m, test_provenance()), ctsurg::InputError);
    EXPECT_FALSE(std::filesystem::exists(dir / "b.h5"));
  };
  bad([](ctsurg::SurfaceMesh& m) { m.uvs.pop_back(); });
  bad([](ctsurg::SurfaceMesh& m) { m.uvs[0] = 1.5f; });
  bad([](ctsurg::SurfaceMesh& m) { m.tangents.resize(12); });
  bad([](ctsurg::SurfaceMesh& m) { m.source_vertex[3] = 7; });
  bad([](ctsurg::SurfaceMesh& m) { m.normal_map.rgb.pop_back(); });
  bad([](ctsurg::SurfaceMesh& m) { m.normal_map.bits = 12; });
  bad([](ctsurg::SurfaceMesh& m) { m.normal_map.rgb[0] = 300; });
  bad([](ctsurg::SurfaceMesh& m) { m.uvs.clear(); });  // a normal map without uvs
}

}  // namespace

// Issue 17: a NaN surface vertex became a NaN trajectory. Non-finite vertices, normals, weights or
// tangents are neither written nor read.
TEST(SurfaceMeshFile, NonFiniteValuesAreNeitherWrittenNorRead) {
  ctsurg::test::TempDir tmp;
  ctsurg::SurfaceMesh m = textured(8);
  m.vertices[4] = std::nanf("");
  EXPECT_THROW(ctsurg::write_surface_mesh_file(tmp / "nan.h5", m, test_provenance()), ctsurg::InputError);
  EXPECT_FALSE(std::filesystem::exists(tmp / "nan.h5"));
  m.vertices[4] = 0.0f;
  ctsurg::write_surface_mesh_file(tmp / "s.h5", m, test_provenance());
  {  // another writer puts a NaN into /surface/normals (HDF5 recomputes its checksum)
    const hid_t file = H5Fopen((tmp / "s.h5").c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    const hid_t ds = H5Dopen2(file, "/surface/normals", H5P_DEFAULT);
    std::vector<float> normals = m.normals;
    normals[7] = std::nanf("");
    ASSERT_GE(H5Dwrite(ds, H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, normals.data()), 0);
    H5Dclose(ds);
    H5Fclose(file);
  }
  try {
    ctsurg::read_surface_mesh_file(tmp / "s.h5");
    ADD_FAILURE() << "a NaN normal was read";
  } catch (const ctsurg::InputError& e) {
    EXPECT_EQ(e.field(), "/surface/normals");
    EXPECT_NE(e.problem().find("row 2, column 1"), std::string::npos) << e.what();
  }
}
