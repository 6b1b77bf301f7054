#include "ctsurg/mesh/tet_mesh_export.h"

#include "ctsurg/core/checked_write.h"
#include "ctsurg/core/error.h"

#include <spdlog/fmt/fmt.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <fstream>
#include <iterator>
#include <limits>
#include <set>

namespace ctsurg {

namespace {

using Buffer = fmt::memory_buffer;

// The cell array is "labels", as SegmentMesher (3D Slicer) writes it, so Slicer and the same
// ParaView/meshio pipelines read both meshers' files alike.
void write_vtu(Buffer& b, const TetMesh& m) {
  const int64_t nn = m.node_count(), nt = m.tet_count();
  auto o = std::back_inserter(b);
  fmt::format_to(o, "<?xml version=\"1.0\"?>\n<!-- ctsurg tet mesh, LPS millimetres -->\n"
                    "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
                    "  <UnstructuredGrid>\n"
                    // 3D Slicer reads the frame from a FieldData string array "SPACE" (vtkMRMLModelStorageNode);
                    // ascii string arrays hold character codes, each string ending in 0: "LPS" = 76 80 83 0.
                    "    <FieldData>\n      <DataArray type=\"String\" Name=\"SPACE\" NumberOfTuples=\"1\" format=\"ascii\">\n"
                    "        76 80 83 0\n      </DataArray>\n    </FieldData>\n"
                    "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n", nn, nt);
  fmt::format_to(o, "      <Points>\n        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n");
  for (int64_t v = 0; v < nn; ++v) {
    const double* p = &m.nodes[static_cast<std::size_t>(3 * v)];
    fmt::format_to(o, "{} {} {}\n", p[0], p[1], p[2]);
  }
  fmt::format_to(o, "        </DataArray>\n      </Points>\n      <Cells>\n"
                    "        <DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">\n");
  for (int64_t t = 0; t < nt; ++t) {
    const int32_t* c = &m.tets[static_cast<std::size_t>(4 * t)];
    fmt::format_to(o, "{} {} {} {}\n", c[0], c[1], c[2], c[3]);
  }
  fmt::format_to(o, "        </DataArray>\n        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
  for (int64_t t = 1; t <= nt; ++t) fmt::format_to(o, "{}\n", 4 * t);
  // VTK_TETRA = 10.
  fmt::format_to(o, "        </DataArray>\n        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
  for (int64_t t = 0; t < nt; ++t) fmt::format_to(o, "10\n");
  fmt::format_to(o, "        </DataArray>\n      </Cells>\n      <CellData Scalars=\"labels\">\n"
                    "        <DataArray type=\"UInt16\" Name=\"labels\" format=\"ascii\">\n");
  for (const uint16_t l : m.tet_labels) fmt::format_to(o, "{}\n", l);
  fmt::format_to(o, "        </DataArray>\n      </CellData>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n");
}

// Gmsh MSH 4.1 ASCII (gmsh.info/doc/texinfo/gmsh.html#MSH-file-format): one volume entity and one
// physical group per label; all nodes in one block on the first volume; element type 4 = tet4.
void write_msh(Buffer& b, const TetMesh& m) {
  const int64_t nn = m.node_count(), nt = m.tet_count();
  const std::set<uint16_t> labels(m.tet_labels.begin(), m.tet_labels.end());
  std::array<double, 6> box{std::numeric_limits<double>::max(), std::numeric_limits<double>::max(),
                            std::numeric_limits<double>::max(), std::numeric_limits<double>::lowest(),
                            std::numeric_limits<double>::lowest(), std::numeric_limits<double>::lowest()};
  for (int64_t v = 0; v < nn; ++v)
    for (std::size_t a = 0; a < 3; ++a) {
      const double x = m.nodes[static_cast<std::size_t>(3 * v) + a];
      box[a] = std::min(box[a], x);
      box[a + 3] = std::max(box[a + 3], x);
    }
  auto o = std::back_inserter(b);
  fmt::format_to(o, "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n{}\n", labels.size());
  for (const uint16_t l : labels) fmt::format_to(o, "3 {} \"label_{}\"\n", l, l);
  fmt::format_to(o, "$EndPhysicalNames\n$Entities\n0 0 0 {}\n", labels.size());
  for (const uint16_t l : labels) {
    fmt::format_to(o, "{} {} {} {} {} {} {} 1 {} 0\n", l, box[0], box[1], box[2], box[3], box[4], box[5], l);
  }
  fmt::format_to(o, "$EndEntities\n$Nodes\n1 {} 1 {}\n3 {} 0 {}\n", nn, nn, *labels.begin(), nn);
  for (int64_t v = 1; v <= nn; ++v) fmt::format_to(o, "{}\n", v);
  for (int64_t v = 0; v < nn; ++v) {
    const double* p = &m.nodes[static_cast<std::size_t>(3 * v)];
    fmt::format_to(o, "{} {} {}\n", p[0], p[1], p[2]);
  }
  fmt::format_to(o, "$EndNodes\n$Elements\n{} {} 1 {}\n", labels.size(), nt, nt);
  int64_t tag = 1;
  for (const uint16_t l : labels) {
    const auto count = std::count(m.tet_labels.begin(), m.tet_labels.end(), l);
    fmt::format_to(o, "3 {} 4 {}\n", l, count);
    for (int64_t t = 0; t < nt; ++t) {
      if (m.tet_labels[static_cast<std::size_t>(t)] != l) continue;
      const int32_t* c = &m.tets[static_cast<std::size_t>(4 * t)];
      fmt::format_to(o, "{} {} {} {} {}\n", tag++, c[0] + 1, c[1] + 1, c[2] + 1, c[3] + 1);
    }
  }
  fmt::format_to(o, "$EndElements\n");
}

// Medit .mesh (INRIA, "MeshVersionFormatted 2": double coordinates), 1-based indices.
void write_medit(Buffer& b, const TetMesh& m) {
  const int64_t nn = m.node_count(), nt = m.tet_count(), nb = m.boundary_face_count();
  auto o = std::back_inserter(b);
  fmt::format_to(o, "MeshVersionFormatted 2\nDimension 3\nVertices\n{}\n", nn);
  for (int64_t v = 0; v < nn; ++v) {
    const double* p = &m.nodes[static_cast<std::size_t>(3 * v)];
    fmt::format_to(o, "{} {} {} 0\n", p[0], p[1], p[2]);
  }
  fmt::format_to(o, "Triangles\n{}\n", nb);
  for (int64_t f = 0; f < nb; ++f) {
    const int32_t* c = &m.boundary_faces[static_cast<std::size_t>(3 * f)];
    fmt::format_to(o, "{} {} {} {}\n", c[0] + 1, c[1] + 1, c[2] + 1, m.face_labels[static_cast<std::size_t>(2 * f)]);
  }
  fmt::format_to(o, "Tetrahedra\n{}\n", nt);
  for (int64_t t = 0; t < nt; ++t) {
    const int32_t* c = &m.tets[static_cast<std::size_t>(4 * t)];
    fmt::format_to(o, "{} {} {} {} {}\n", c[0] + 1, c[1] + 1, c[2] + 1, c[3] + 1, m.tet_labels[static_cast<std::size_t>(t)]);
  }
  fmt::format_to(o, "End\n");
}

}  // namespace

std::string tet_mesh_export_format(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".vtu") return "vtu";
  if (ext == ".msh") return "msh";
  if (ext == ".mesh") return "mesh";
  return "";
}

void export_tet_mesh(const std::filesystem::path& path, const TetMesh& mesh, const std::filesystem::path& format_of) {
  const std::filesystem::path named = format_of.empty() ? path : format_of;
  const std::string format = tet_mesh_export_format(named);
  if (format.empty()) throw InputError(named.string(), "suffix", "unknown output format; use .h5, .vtu, .msh or .mesh");
  validate_tet_mesh(mesh, named.string());
  Buffer b;
  if (format == "vtu") write_vtu(b, mesh);
  if (format == "msh") write_msh(b, mesh);
  if (format == "mesh") write_medit(b, mesh);
  write_file_checked(path, std::string_view(b.data(), b.size()), named.string());
}

}  // namespace ctsurg
