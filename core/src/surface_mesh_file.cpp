#include "ctsurg/core/surface_mesh_file.h"

#include "ctsurg/core/ctsurg_file.h"
#include "ctsurg/core/error.h"
#include "ctsurg/core/finite_values.h"
#include "ctsurg/core/hdf5_file.h"

#include <array>
#include <sstream>

namespace ctsurg {

namespace {

// XDMF 3 triangle mesh pointing into the HDF5 file: ParaView shows the surface with its normals.
std::string surface_xdmf(const std::string& h5_name, int64_t nv, int64_t nf) {
  const std::string v = std::to_string(nv), f = std::to_string(nf);
  std::ostringstream x;
  x << "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
    << "<!-- ctsurg sidecar: opens " << h5_name << " in ParaView. LPS millimetres. -->\n"
    << "<Xdmf Version=\"3.0\">\n  <Domain>\n"
    << "    <Grid Name=\"surface\" GridType=\"Uniform\">\n"
    << "      <Topology TopologyType=\"Triangle\" NumberOfElements=\"" << f << "\">\n"
    << "        <DataItem Dimensions=\"" << f << " 3\" NumberType=\"UInt\" Precision=\"4\" Format=\"HDF\">" << h5_name
    << ":/surface/triangles</DataItem>\n"
    << "      </Topology>\n"
    << "      <Geometry GeometryType=\"XYZ\">\n"
    << "        <DataItem Dimensions=\"" << v << " 3\" NumberType=\"Float\" Precision=\"4\" Format=\"HDF\">" << h5_name
    << ":/surface/vertices</DataItem>\n"
    << "      </Geometry>\n"
    << "      <Attribute Name=\"normals\" AttributeType=\"Vector\" Center=\"Node\">\n"
    << "        <DataItem Dimensions=\"" << v << " 3\" NumberType=\"Float\" Precision=\"4\" Format=\"HDF\">" << h5_name
    << ":/surface/normals</DataItem>\n"
    << "      </Attribute>\n"
    << "    </Grid>\n  </Domain>\n</Xdmf>\n";
  return x.str();
}

void check_sizes(const SurfaceMesh& m, const std::string& file) {
  const std::size_t nv = m.vertices.size() / 3;
  if (m.vertices.size() % 3 != 0 || m.triangles.size() % 3 != 0) {
    throw InputError(file, "/surface", "vertex or triangle array is not a multiple of 3 long");
  }
  if (nv == 0 || m.triangles.empty()) throw InputError(file, "/surface", "the mesh is empty");
  if (m.normals.size() != 3 * nv || m.grid_cell.size() != 3 * nv || m.grid_weights.size() != 8 * nv ||
      m.nearest_node.size() != 3 * nv) {
    throw InputError(file, "/surface", "per-vertex arrays differ in length from the vertex array");
  }
  if ((!m.uvs.empty() && m.uvs.size() != 2 * nv) || (!m.tangents.empty() && m.tangents.size() != 4 * nv) ||
      (!m.source_vertex.empty() && m.source_vertex.size() != nv)) {
    throw InputError(file, "/surface",
                     "optional per-vertex arrays (uvs, tangents, source_vertex) differ in length from the vertex array");
  }
  require_finite(m.vertices, 3, file, "/surface/vertices");
  require_finite(m.normals, 3, file, "/surface/normals");
  require_finite(m.grid_weights, 8, file, "/surface/grid_weights");
  require_finite(m.tangents, 4, file, "/surface/tangents");
  for (const float u : m.uvs) {
    if (!(u >= 0.0f && u <= 1.0f)) throw InputError(file, "/surface/uvs", "texture coordinates must lie in [0, 1]");
  }
  for (const uint32_t v : m.source_vertex) {
    if (v >= static_cast<uint64_t>(m.source_vertex_count)) {
      throw InputError(file, "/surface/source_vertex", "index " + std::to_string(v) + " is not below @source_vertices (" +
                                                            std::to_string(m.source_vertex_count) + ")");
    }
  }
  const NormalMapImage& img = m.normal_map;
  if (!img.empty()) {
    if (img.width <= 0 || img.height <= 0 || img.rgb.size() != static_cast<std::size_t>(3 * img.width * img.height)) {
      throw InputError(file, "/surface/normal_map", "size does not match width x height x 3");
    }
    if (img.bits != 8 && img.bits != 16) throw InputError(file, "/surface/normal_map", "bits must be 8 or 16");
    if (img.bits == 8) {
      for (const uint16_t c : img.rgb) {
        if (c > 255) throw InputError(file, "/surface/normal_map", "an 8-bit map holds a value above 255");
      }
    }
    if (m.uvs.empty()) throw InputError(file, "/surface/normal_map", "a normal map needs texture coordinates (uvs)");
  }
}

}  // namespace

void write_surface_mesh_file(const std::filesystem::path& path, const SurfaceMesh& mesh, const Provenance& provenance,
                             OutputUnit* unit) {
  check_sizes(mesh, path.string());
  const uint64_t nv = static_cast<uint64_t>(mesh.vertex_count()), nf = static_cast<uint64_t>(mesh.triangle_count());
  write_ctsurg_file(
      path, "surface_mesh", 1, provenance,
      [&](h5::Group& root) {
        h5::Group s = root.create_group("surface");
        s.set_attribute("frame", std::string("LPS"));
        s.set_attribute("units", std::string("mm"));
        s.set_attribute("iso", mesh.iso);
        s.set_attribute("quantity", mesh.quantity);
        s.set_attribute("source_dataset", mesh.source_dataset);
        s.set_attribute("vertices", static_cast<int64_t>(nv));
        s.set_attribute("triangles", static_cast<int64_t>(nf));
        const auto& g = mesh.lattice;
        const std::array<int64_t, 3> dims = g.dims;
        const std::array<double, 3> spacing{g.spacing[0], g.spacing[1], g.spacing[2]};
        const std::array<double, 3> origin{g.origin[0], g.origin[1], g.origin[2]};
        std::array<double, 9> direction{};
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) direction[static_cast<std::size_t>(3 * r + c)] = g.direction(r, c);
        s.set_attribute("dims", std::span<const int64_t>(dims));
        s.set_attribute("spacing_mm", std::span<const double>(spacing));
        s.set_attribute("origin_mm", std::span<const double>(origin));
        s.set_attribute("direction", std::span<const double>(direction));
        const std::array<uint64_t, 2> v3{nv, 3}, v8{nv, 8}, f3{nf, 3};
        s.write_dataset("vertices", mesh.vertices, v3);
        s.write_dataset("normals", mesh.normals, v3);
        s.write_dataset("triangles", mesh.triangles, f3);
        s.write_dataset("grid_cell", mesh.grid_cell, v3);
        s.write_dataset("grid_weights", mesh.grid_weights, v8);
        s.write_dataset("nearest_node", mesh.nearest_node, v3);
        if (!mesh.uvs.empty()) s.write_dataset("uvs", mesh.uvs, std::array<uint64_t, 2>{nv, 2});
        if (!mesh.tangents.empty()) s.write_dataset("tangents", mesh.tangents, std::array<uint64_t, 2>{nv, 4});
        if (!mesh.source_vertex.empty()) {
          s.write_dataset("source_vertex", mesh.source_vertex, std::array<uint64_t, 1>{nv});
          s.set_attribute("source_vertices", mesh.source_vertex_count);
        }
        const NormalMapImage& img = mesh.normal_map;
        if (!img.empty()) {
          const std::array<uint64_t, 3> shape{static_cast<uint64_t>(img.height), static_cast<uint64_t>(img.width), 3};
          if (img.bits == 8) {
            const std::vector<uint8_t> bytes(img.rgb.begin(), img.rgb.end());
            s.write_dataset("normal_map", bytes, shape);
          } else {
            s.write_dataset("normal_map", img.rgb, shape);
          }
          s.set_attribute("normal_map_space", std::string("tangent"));
          s.set_attribute("normal_map_bits", static_cast<int64_t>(img.bits));
        }
      },
      surface_xdmf(path.filename().string(), mesh.vertex_count(), mesh.triangle_count()), unit);
}

SurfaceMesh read_surface_mesh_file(const std::filesystem::path& path) {
  const h5::File f = open_ctsurg_file(path, "surface_mesh");
  const h5::Group s = f.root().open_group("surface");
  const std::string file = path.string();
  SurfaceMesh m;
  std::vector<uint64_t> shape;
  const auto read = [&](const char* name, auto& out, uint64_t cols, uint64_t rows) {
    using T = typename std::decay_t<decltype(out)>::value_type;
    out = s.read_dataset<T>(name, &shape);
    if (shape.size() != 2 || shape[1] != cols || (rows != 0 && shape[0] != rows)) {
      throw InputError(file, s.path() + "/" + name, "expected shape (" + (rows ? std::to_string(rows) : std::string("n")) +
                                                        ", " + std::to_string(cols) + ")");
    }
  };
  read("vertices", m.vertices, 3, 0);
  const uint64_t nv = shape[0];
  read("normals", m.normals, 3, nv);
  read("triangles", m.triangles, 3, 0);
  read("grid_cell", m.grid_cell, 3, nv);
  read("grid_weights", m.grid_weights, 8, nv);
  read("nearest_node", m.nearest_node, 3, nv);
  if (s.has("uvs")) read("uvs", m.uvs, 2, nv);
  if (s.has("tangents")) read("tangents", m.tangents, 4, nv);
  if (s.has("source_vertex")) {
    m.source_vertex = s.read_dataset<uint32_t>("source_vertex", &shape);
    if (shape.size() != 1 || shape[0] != nv) throw InputError(file, s.path() + "/source_vertex", "expected shape (#V)");
    m.source_vertex_count = s.int_attribute("source_vertices");
  }
  if (s.has("normal_map")) {
    m.normal_map.rgb = s.read_dataset<uint16_t>("normal_map", &shape);
    if (shape.size() != 3 || shape[2] != 3) throw InputError(file, s.path() + "/normal_map", "expected shape (H, W, 3)");
    m.normal_map.height = static_cast<int64_t>(shape[0]);
    m.normal_map.width = static_cast<int64_t>(shape[1]);
    m.normal_map.bits = static_cast<int>(s.int_attribute("normal_map_bits"));
    if (s.string_attribute("normal_map_space") != "tangent") {
      throw InputError(file, s.path() + "@normal_map_space", "only tangent-space normal maps are known");
    }
  }
  for (const uint32_t t : m.triangles) {
    if (t >= nv) throw InputError(file, s.path() + "/triangles", "vertex index " + std::to_string(t) + " out of range");
  }
  m.iso = s.double_attribute("iso");
  m.quantity = s.string_attribute("quantity");
  m.source_dataset = s.string_attribute("source_dataset");
  const auto dims = s.ints_attribute("dims");
  const auto spacing = s.doubles_attribute("spacing_mm");
  const auto origin = s.doubles_attribute("origin_mm");
  const auto direction = s.doubles_attribute("direction");
  if (dims.size() != 3 || spacing.size() != 3 || origin.size() != 3 || direction.size() != 9) {
    throw InputError(file, s.path(), "lattice attributes dims/spacing_mm/origin_mm/direction have the wrong length");
  }
  for (int a = 0; a < 3; ++a) {
    m.lattice.dims[static_cast<std::size_t>(a)] = dims[static_cast<std::size_t>(a)];
    m.lattice.spacing[a] = spacing[static_cast<std::size_t>(a)];
    m.lattice.origin[a] = origin[static_cast<std::size_t>(a)];
  }
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m.lattice.direction(r, c) = direction[static_cast<std::size_t>(3 * r + c)];
  m.lattice.validate(file + ": " + s.path());
  check_sizes(m, file);
  return m;
}

}  // namespace ctsurg
