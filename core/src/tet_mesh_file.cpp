#include "ctsurg/core/tet_mesh_file.h"

#include "ctsurg/core/ctsurg_file.h"
#include "ctsurg/core/error.h"
#include "ctsurg/core/finite_values.h"
#include "ctsurg/core/hdf5_file.h"

#include <algorithm>
#include <array>
#include <set>
#include <sstream>

namespace ctsurg {

namespace {

// XDMF 3 tetrahedral mesh pointing into the HDF5 file: ParaView shows the tets coloured by label.
std::string tet_mesh_xdmf(const std::string& h5_name, int64_t nn, int64_t nt) {
  const std::string n = std::to_string(nn), t = std::to_string(nt);
  std::ostringstream x;
  x << "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
    << "<!-- ctsurg sidecar: opens " << h5_name << " in ParaView. LPS millimetres. -->\n"
    << "<Xdmf Version=\"3.0\">\n  <Domain>\n"
    << "    <Grid Name=\"tetmesh\" GridType=\"Uniform\">\n"
    << "      <Topology TopologyType=\"Tetrahedron\" NumberOfElements=\"" << t << "\">\n"
    << "        <DataItem Dimensions=\"" << t << " 4\" NumberType=\"Int\" Precision=\"4\" Format=\"HDF\">" << h5_name
    << ":/tetmesh/tets</DataItem>\n"
    << "      </Topology>\n"
    << "      <Geometry GeometryType=\"XYZ\">\n"
    << "        <DataItem Dimensions=\"" << n << " 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" << h5_name
    << ":/tetmesh/nodes</DataItem>\n"
    << "      </Geometry>\n"
    << "      <Attribute Name=\"label\" AttributeType=\"Scalar\" Center=\"Cell\">\n"
    << "        <DataItem Dimensions=\"" << t << "\" NumberType=\"UInt\" Precision=\"2\" Format=\"HDF\">" << h5_name
    << ":/tetmesh/tet_labels</DataItem>\n"
    << "      </Attribute>\n"
    << "    </Grid>\n  </Domain>\n</Xdmf>\n";
  return x.str();
}

}  // namespace

void validate_tet_mesh(const TetMesh& m, const std::string& file) {
  if (m.nodes.size() % 3 != 0 || m.tets.size() % 4 != 0 || m.boundary_faces.size() % 3 != 0) {
    throw InputError(file, "/tetmesh", "node, tet or face array has a length that is not a multiple of its row size");
  }
  if (m.nodes.empty() || m.tets.empty()) throw InputError(file, "/tetmesh", "the mesh is empty");
  if (m.tet_labels.size() != m.tets.size() / 4) {
    throw InputError(file, "/tetmesh/tet_labels", "expected one label per tet");
  }
  if (m.face_labels.size() != 2 * (m.boundary_faces.size() / 3)) {
    throw InputError(file, "/tetmesh/face_labels", "expected two labels per boundary face");
  }
  require_finite(m.nodes, 3, file, "/tetmesh/nodes");
  const int64_t nn = m.node_count();
  const auto check_indices = [&](const std::vector<int32_t>& idx, const char* name) {
    for (const int32_t i : idx) {
      if (i < 0 || i >= nn) {
        throw InputError(file, std::string("/tetmesh/") + name,
                         "node index " + std::to_string(i) + " out of range [0, " + std::to_string(nn) + ")");
      }
    }
  };
  check_indices(m.tets, "tets");
  check_indices(m.boundary_faces, "boundary_faces");
  const auto& q = m.quality;
  if (q.radius_edge_bin_edges.size() != q.radius_edge_histogram.size() + 1 || q.radius_edge_histogram.empty()) {
    throw InputError(file, "/tetmesh/quality", "radius-edge histogram needs #bins + 1 bin edges and at least one bin");
  }
}

void write_tet_mesh_file(const std::filesystem::path& path, const TetMesh& mesh, const Provenance& provenance) {
  validate_tet_mesh(mesh, path.string());
  const uint64_t nn = static_cast<uint64_t>(mesh.node_count()), nt = static_cast<uint64_t>(mesh.tet_count()),
                 nb = static_cast<uint64_t>(mesh.boundary_face_count());
  write_ctsurg_file(
      path, "tet_mesh", 1, provenance,
      [&](h5::Group& root) {
        h5::Group s = root.create_group("tetmesh");
        s.set_attribute("frame", std::string("LPS"));
        s.set_attribute("units", std::string("mm"));
        s.set_attribute("nodes", static_cast<int64_t>(nn));
        s.set_attribute("tets", static_cast<int64_t>(nt));
        s.set_attribute("boundary_faces", static_cast<int64_t>(nb));
        s.set_attribute("mask_volume_mm3", mesh.mask_volume_mm3);
        s.set_attribute("seed", static_cast<int64_t>(mesh.seed));
        s.set_attribute("criteria", mesh.criteria);
        const std::set<uint16_t> label_set(mesh.tet_labels.begin(), mesh.tet_labels.end());
        const std::vector<int64_t> labels(label_set.begin(), label_set.end());
        s.set_attribute("labels", std::span<const int64_t>(labels));
        const std::array<uint64_t, 2> n3{nn, 3}, t4{nt, 4}, b3{nb, 3}, b2{nb, 2};
        const std::array<uint64_t, 1> t1{nt};
        s.write_dataset("nodes", mesh.nodes, n3);
        s.write_dataset("tets", mesh.tets, t4);
        s.write_dataset("tet_labels", mesh.tet_labels, t1);
        s.write_dataset("boundary_faces", mesh.boundary_faces, b3);
        s.write_dataset("face_labels", mesh.face_labels, b2);
        const auto& q = mesh.quality;
        h5::Group g = s.create_group("quality");
        g.set_attribute("min_dihedral_deg", q.min_dihedral_deg);
        g.set_attribute("max_dihedral_deg", q.max_dihedral_deg);
        g.set_attribute("min_radius_edge", q.min_radius_edge);
        g.set_attribute("mean_radius_edge", q.mean_radius_edge);
        g.set_attribute("max_radius_edge", q.max_radius_edge);
        g.set_attribute("slivers", q.slivers);
        g.set_attribute("sliver_threshold_deg", q.sliver_threshold_deg);
        g.set_attribute("inverted", q.inverted);
        g.set_attribute("volume_mm3", q.volume_mm3);
        g.set_attribute("radius_edge_bin_edges", std::span<const double>(q.radius_edge_bin_edges));
        const std::array<uint64_t, 1> h1{q.radius_edge_histogram.size()};
        g.write_dataset("radius_edge_histogram", q.radius_edge_histogram, h1);
      },
      tet_mesh_xdmf(path.filename().string(), mesh.node_count(), mesh.tet_count()));
}

TetMesh read_tet_mesh_file(const std::filesystem::path& path) {
  const h5::File f = open_ctsurg_file(path, "tet_mesh");
  const h5::Group s = f.root().open_group("tetmesh");
  const std::string file = path.string();
  TetMesh m;
  std::vector<uint64_t> shape;
  // cols == 0: a 1-D dataset; rows == 0: any number of rows.
  const auto read = [&](const h5::Group& g, const char* name, auto& out, uint64_t cols, uint64_t rows) {
    using T = typename std::decay_t<decltype(out)>::value_type;
    out = g.template read_dataset<T>(name, &shape);
    const bool ok = cols == 0 ? shape.size() == 1 : (shape.size() == 2 && shape[1] == cols);
    if (!ok || (rows != 0 && shape[0] != rows)) {
      const std::string r = rows ? std::to_string(rows) : std::string("n");
      throw InputError(file, g.path() + "/" + name,
                       "expected shape (" + r + (cols ? ", " + std::to_string(cols) : std::string()) + ")");
    }
  };
  read(s, "nodes", m.nodes, 3, 0);
  read(s, "tets", m.tets, 4, 0);
  const uint64_t nt = shape[0];
  read(s, "tet_labels", m.tet_labels, 0, nt);
  read(s, "boundary_faces", m.boundary_faces, 3, 0);
  const uint64_t nb = shape[0];
  read(s, "face_labels", m.face_labels, 2, nb);
  m.mask_volume_mm3 = s.double_attribute("mask_volume_mm3");
  m.seed = static_cast<uint64_t>(s.int_attribute("seed"));
  m.criteria = s.string_attribute("criteria");
  const h5::Group g = s.open_group("quality");
  auto& q = m.quality;
  q.min_dihedral_deg = g.double_attribute("min_dihedral_deg");
  q.max_dihedral_deg = g.double_attribute("max_dihedral_deg");
  q.min_radius_edge = g.double_attribute("min_radius_edge");
  q.mean_radius_edge = g.double_attribute("mean_radius_edge");
  q.max_radius_edge = g.double_attribute("max_radius_edge");
  q.slivers = g.int_attribute("slivers");
  q.sliver_threshold_deg = g.double_attribute("sliver_threshold_deg");
  q.inverted = g.int_attribute("inverted");
  q.volume_mm3 = g.double_attribute("volume_mm3");
  q.radius_edge_bin_edges = g.doubles_attribute("radius_edge_bin_edges");
  read(g, "radius_edge_histogram", q.radius_edge_histogram, 0, 0);
  validate_tet_mesh(m, file);
  return m;
}

}  // namespace ctsurg
