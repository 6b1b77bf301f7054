#include "ctsurg/mesh/tet_mesh_import.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/input_file.h"
#include "ctsurg/mesh/tet_mesh_export.h"
#include "ctsurg/mesh/tet_mesh_quality.h"

#include <nlohmann/json.hpp>
#include <spdlog/fmt/fmt.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <unordered_map>

namespace ctsurg {

namespace {

// What a reader hands over: nodes as in the file, tets as 0-based indices into them.
struct RawMesh {
  std::vector<double> nodes;
  std::vector<int64_t> tets;  // #T x 4
  std::vector<int64_t> labels;
  int64_t skipped = 0;
  bool labels_from_file = true;
  std::string format;
};

std::string read_import_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  if (!in && !in.eof()) throw RuntimeError(path.string() + ": read failed");
  return s.str();
}

// Whitespace-separated tokens with a position for messages.
class Tokens {
 public:
  Tokens(const std::string& text, std::string file) : text_(text), file_(std::move(file)) {}
  bool done() {
    skip();
    return at_ >= text_.size();
  }
  std::string next(const std::string& what) {
    skip();
    if (at_ >= text_.size()) throw InputError(file_, what, "the file ends early");
    const std::size_t b = at_;
    while (at_ < text_.size() && !std::isspace(static_cast<unsigned char>(text_[at_]))) ++at_;
    return text_.substr(b, at_ - b);
  }
  int64_t integer(const std::string& what) {
    const std::string t = next(what);
    try {
      std::size_t used = 0;
      const long long v = std::stoll(t, &used);
      if (used == t.size()) return v;
    } catch (const std::exception&) {
    }
    throw InputError(file_, what, "'" + t.substr(0, 40) + "' is not a whole number");
  }
  double real(const std::string& what) {
    const std::string t = next(what);
    try {
      std::size_t used = 0;
      const double v = std::stod(t, &used);
      if (used == t.size() && std::isfinite(v)) return v;
    } catch (const std::exception&) {
    }
    throw InputError(file_, what, "'" + t.substr(0, 40) + "' is not a finite number");
  }
  // Skips the rest of the current line.
  void line() {
    while (at_ < text_.size() && text_[at_] != '\n') ++at_;
  }
  bool comments = false;  // '#' starts a comment (Medit)
  // Bytes of text not yet read.
  std::size_t remaining() const { return text_.size() - std::min(at_, text_.size()); }

 private:
  void skip() {
    while (at_ < text_.size()) {
      if (std::isspace(static_cast<unsigned char>(text_[at_]))) {
        ++at_;
      } else if (comments && text_[at_] == '#') {
        line();
      } else {
        break;
      }
    }
  }
  const std::string& text_;
  std::string file_;
  std::size_t at_ = 0;
};

// A count read from the file. Each counted item takes at least one token and a separator (2 bytes)
// of what is left, so a count the rest of the file cannot hold is refused before anything is reserved
// for it (a fuzzed Medit file declared 935,854,226 vertices in 637 bytes: 22 GB reserved).
int64_t count_of(Tokens& t, const std::string& what, const std::string& file, int64_t max = int64_t{1} << 31) {
  const int64_t n = t.integer(what);
  if (n < 0 || n >= max) throw InputError(file, what, fmt::format("count {} out of range", n));
  if (static_cast<uint64_t>(n) > t.remaining() / 2) {
    throw InputError(file, what, fmt::format("count {} is more than the {} bytes left in the file can hold", n, t.remaining()));
  }
  return n;
}

// ---- Medit .mesh (INRIA, "MeshVersionFormatted"; keywords followed by a count and rows) ----
RawMesh read_medit(const std::string& text, const std::string& file) {
  RawMesh m;
  m.format = "mesh";
  Tokens t(text, file);
  t.comments = true;
  // Values per row of each keyword we read past.
  static const std::map<std::string, int> skip_rows = {
      {"edges", 3},          {"triangles", 4},       {"quadrilaterals", 5},   {"hexahedra", 9},
      {"prisms", 7},         {"corners", 1},         {"requiredvertices", 1}, {"ridges", 1},
      {"requirededges", 1},  {"requiredtriangles", 1}, {"normals", 3},        {"tangents", 3},
      {"normalatvertices", 2}, {"tangentatvertices", 2}, {"identifier", 0}};
  bool have_vertices = false;
  while (!t.done()) {
    std::string key = t.next("keyword");
    std::transform(key.begin(), key.end(), key.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (key == "end") break;
    if (key == "meshversionformatted") {
      const int64_t v = t.integer("MeshVersionFormatted");
      if (v < 1 || v > 2) throw InputError(file, "MeshVersionFormatted", fmt::format("{}: only 1 and 2 (ASCII) are read", v));
    } else if (key == "dimension") {
      const int64_t d = t.integer("Dimension");
      if (d != 3) throw InputError(file, "Dimension", fmt::format("{}: a tet mesh needs 3", d));
    } else if (key == "vertices") {
      const int64_t n = count_of(t, "Vertices", file);
      m.nodes.reserve(static_cast<std::size_t>(3 * n));
      for (int64_t v = 0; v < n; ++v) {
        for (int a = 0; a < 3; ++a) m.nodes.push_back(t.real(fmt::format("Vertices row {}", v + 1)));
        t.integer(fmt::format("Vertices row {} reference", v + 1));
      }
      have_vertices = true;
    } else if (key == "tetrahedra") {
      const int64_t n = count_of(t, "Tetrahedra", file);
      for (int64_t e = 0; e < n; ++e) {
        const std::string what = fmt::format("Tetrahedra row {}", e + 1);
        for (int a = 0; a < 4; ++a) m.tets.push_back(t.integer(what) - 1);
        m.labels.push_back(t.integer(what + " reference"));
      }
    } else if (const auto it = skip_rows.find(key); it != skip_rows.end()) {
      if (key == "identifier") {
        t.line();
        continue;
      }
      const int64_t n = count_of(t, key, file);
      for (int64_t r = 0; r < n * it->second; ++r) t.next(key);
      if (key != "corners" && key != "requiredvertices" && key != "ridges" && key != "requirededges" &&
          key != "requiredtriangles" && key != "normals" && key != "tangents" && key != "normalatvertices" &&
          key != "tangentatvertices")
        m.skipped += n;
    } else {
      throw InputError(file, key, "unknown Medit keyword (not read past safely)");
    }
  }
  if (!have_vertices) throw InputError(file, "Vertices", "absent");
  return m;
}

// ---- Gmsh MSH 2.2 / 4.1 ASCII (gmsh.info/doc/texinfo/gmsh.html#MSH-file-format) ----
RawMesh read_gmsh(const std::string& text, const std::string& file) {
  RawMesh m;
  Tokens t(text, file);
  if (t.next("$MeshFormat") != "$MeshFormat") throw InputError(file, "$MeshFormat", "not a Gmsh file (no $MeshFormat first)");
  const std::string version = t.next("$MeshFormat version");
  const int64_t binary = t.integer("$MeshFormat file-type");
  t.integer("$MeshFormat data-size");
  if (binary != 0) throw InputError(file, "$MeshFormat", "binary MSH is not read; save as ASCII (Gmsh: -format msh22 or msh41 -save_all, ASCII)");
  const bool v4 = version.rfind("4", 0) == 0;
  if (!v4 && version.rfind("2", 0) != 0) throw InputError(file, "$MeshFormat", "version " + version + ": only 2.2 and 4.1 are read");
  if (v4 && version != "4.1") throw InputError(file, "$MeshFormat", "version " + version + ": only 2.2 and 4.1 are read");
  m.format = v4 ? "msh 4.1" : "msh 2.2";
  if (t.next("$EndMeshFormat") != "$EndMeshFormat") throw InputError(file, "$MeshFormat", "no $EndMeshFormat");
  std::unordered_map<int64_t, int64_t> node_of_tag;
  std::map<int64_t, int64_t> volume_physical;  // 4.1: volume entity tag -> first physical tag
  std::vector<int64_t> tet_tags;               // node tags, resolved after reading
  bool have_nodes = false;
  const auto skip_section = [&](const std::string& name) {
    const std::string end = "$End" + name.substr(1);
    while (t.next(name) != end) {
    }
  };
  while (!t.done()) {
    const std::string section = t.next("section");
    if (section == "$Nodes") {
      have_nodes = true;
      if (!v4) {
        const int64_t n = count_of(t, "$Nodes", file);
        for (int64_t v = 0; v < n; ++v) {
          const int64_t tag = t.integer("$Nodes tag");
          node_of_tag[tag] = static_cast<int64_t>(m.nodes.size() / 3);
          for (int a = 0; a < 3; ++a) m.nodes.push_back(t.real(fmt::format("$Nodes node {}", tag)));
        }
      } else {
        const int64_t blocks = count_of(t, "$Nodes", file);
        count_of(t, "$Nodes", file);
        t.integer("$Nodes");
        t.integer("$Nodes");
        for (int64_t b = 0; b < blocks; ++b) {
          t.integer("$Nodes entityDim");
          t.integer("$Nodes entityTag");
          if (t.integer("$Nodes parametric") != 0) throw InputError(file, "$Nodes", "parametric nodes are not read");
          const int64_t n = count_of(t, "$Nodes numNodesInBlock", file);
          std::vector<int64_t> tags(static_cast<std::size_t>(n));
          for (auto& tag : tags) tag = t.integer("$Nodes tag");
          for (const int64_t tag : tags) {
            node_of_tag[tag] = static_cast<int64_t>(m.nodes.size() / 3);
            for (int a = 0; a < 3; ++a) m.nodes.push_back(t.real(fmt::format("$Nodes node {}", tag)));
          }
        }
      }
      if (t.next("$EndNodes") != "$EndNodes") throw InputError(file, "$Nodes", "no $EndNodes where the nodes end");
    } else if (section == "$Entities" && v4) {
      const int64_t np = count_of(t, "$Entities", file), nc = count_of(t, "$Entities", file),
                    ns = count_of(t, "$Entities", file), nv = count_of(t, "$Entities", file);
      for (int64_t e = 0; e < np; ++e) {
        t.integer("$Entities point");
        for (int a = 0; a < 3; ++a) t.real("$Entities point");
        const int64_t k = count_of(t, "$Entities point", file);
        for (int64_t i = 0; i < k; ++i) t.integer("$Entities point");
      }
      for (int64_t dim = 1; dim <= 3; ++dim) {
        const int64_t n = dim == 1 ? nc : dim == 2 ? ns : nv;
        for (int64_t e = 0; e < n; ++e) {
          const int64_t tag = t.integer("$Entities tag");
          for (int a = 0; a < 6; ++a) t.real("$Entities box");
          const int64_t k = count_of(t, "$Entities physical tags", file);
          for (int64_t i = 0; i < k; ++i) {
            const int64_t p = t.integer("$Entities physical tag");
            if (dim == 3 && i == 0) volume_physical[tag] = p;
          }
          const int64_t kb = count_of(t, "$Entities bounding", file);
          for (int64_t i = 0; i < kb; ++i) t.integer("$Entities bounding");
        }
      }
      if (t.next("$EndEntities") != "$EndEntities") throw InputError(file, "$Entities", "no $EndEntities");
    } else if (section == "$Elements") {
      if (!v4) {
        const int64_t n = count_of(t, "$Elements", file);
        for (int64_t e = 0; e < n; ++e) {
          const int64_t tag = t.integer("$Elements tag");
          const int64_t type = t.integer(fmt::format("$Elements element {} type", tag));
          const int64_t ntags = count_of(t, fmt::format("$Elements element {} tags", tag), file, 64);
          std::vector<int64_t> tags(static_cast<std::size_t>(ntags));
          for (auto& x : tags) x = t.integer(fmt::format("$Elements element {} tag", tag));
          // Nodes per element type (MSH 2.2 table): enough for the linear and quadratic types.
          static const std::map<int64_t, int> nodes_of = {{1, 2},  {2, 3},  {3, 4},  {4, 4},  {5, 8},  {6, 6},
                                                          {7, 5},  {8, 3},  {9, 6},  {10, 9}, {11, 10}, {12, 27},
                                                          {13, 18}, {14, 14}, {15, 1}, {16, 8}, {17, 20}, {18, 15},
                                                          {19, 13}};
          const auto nt = nodes_of.find(type);
          if (nt == nodes_of.end()) throw InputError(file, fmt::format("$Elements element {}", tag), fmt::format("element type {} is not known", type));
          if (type != 4) {
            for (int i = 0; i < nt->second; ++i) t.integer("$Elements node");
            ++m.skipped;
            continue;
          }
          for (int i = 0; i < 4; ++i) tet_tags.push_back(t.integer(fmt::format("$Elements element {} node", tag)));
          m.labels.push_back(!tags.empty() && tags[0] != 0 ? tags[0] : tags.size() > 1 ? tags[1] : 1);
        }
      } else {
        const int64_t blocks = count_of(t, "$Elements", file);
        count_of(t, "$Elements", file);
        t.integer("$Elements");
        t.integer("$Elements");
        for (int64_t b = 0; b < blocks; ++b) {
          const int64_t dim = t.integer("$Elements entityDim");
          const int64_t entity = t.integer("$Elements entityTag");
          const int64_t type = t.integer("$Elements elementType");
          const int64_t n = count_of(t, "$Elements numElementsInBlock", file);
          if (type != 4) {
            // Read past by lines: one element per line.
            for (int64_t e = 0; e < n; ++e) {
              t.integer("$Elements tag");
              t.line();
            }
            m.skipped += n;
            continue;
          }
          (void)dim;
          const auto ph = volume_physical.find(entity);
          const int64_t label = ph != volume_physical.end() ? ph->second : entity;
          for (int64_t e = 0; e < n; ++e) {
            const int64_t tag = t.integer("$Elements tag");
            for (int i = 0; i < 4; ++i) tet_tags.push_back(t.integer(fmt::format("$Elements element {} node", tag)));
            m.labels.push_back(label);
          }
        }
      }
      if (t.next("$EndElements") != "$EndElements") throw InputError(file, "$Elements", "no $EndElements where the elements end");
    } else if (!section.empty() && section[0] == '$' && section.rfind("$End", 0) != 0) {
      skip_section(section);
    } else {
      throw InputError(file, "section", "'" + section.substr(0, 40) + "' where a $Section was expected");
    }
  }
  if (!have_nodes) throw InputError(file, "$Nodes", "absent");
  m.tets.reserve(tet_tags.size());
  for (std::size_t i = 0; i < tet_tags.size(); ++i) {
    const auto it = node_of_tag.find(tet_tags[i]);
    if (it == node_of_tag.end()) {
      throw InputError(file, fmt::format("$Elements tet {}", i / 4 + 1), fmt::format("node tag {} is not in $Nodes", tet_tags[i]));
    }
    m.tets.push_back(it->second);
  }
  return m;
}

// ---- VTK XML UnstructuredGrid, ascii data arrays ----
std::string attribute(const std::string& tag, const std::string& name) {
  const std::string key = " " + name + "=\"";
  const auto at = tag.find(key);
  if (at == std::string::npos) return "";
  const auto b = at + key.size();
  return tag.substr(b, tag.find('"', b) - b);
}

struct XmlArray {
  std::string tag;   // the opening tag's text
  std::string body;  // between the tags
};

// The DataArrays between `open` and its closing tag ("" when the section is absent).
std::vector<XmlArray> arrays_in(const std::string& text, const std::string& section, const std::string& file) {
  std::vector<XmlArray> out;
  const auto b = text.find("<" + section);
  if (b == std::string::npos) return out;
  const auto e = text.find("</" + section + ">", b);
  if (e == std::string::npos) throw InputError(file, section, "no closing </" + section + ">");
  std::size_t at = b;
  while (true) {
    const auto a = text.find("<DataArray", at);
    if (a == std::string::npos || a > e) break;
    const auto close = text.find('>', a);
    if (close == std::string::npos) throw InputError(file, section, "unterminated <DataArray");
    XmlArray x;
    x.tag = text.substr(a, close - a + 1);
    if (x.tag.size() >= 2 && x.tag[x.tag.size() - 2] == '/') {
      at = close + 1;
      out.push_back(x);
      continue;
    }
    const auto end = text.find("</DataArray>", close);
    if (end == std::string::npos || end > e) throw InputError(file, section, "unterminated <DataArray>");
    x.body = text.substr(close + 1, end - close - 1);
    out.push_back(x);
    at = end;
  }
  return out;
}

template <class T>
std::vector<T> ascii_values(const XmlArray& a, const std::string& file, const std::string& what) {
  const std::string format = attribute(a.tag, "format");
  if (format != "ascii") {
    throw InputError(file, what, "format=\"" + format + "\": only ascii data arrays are read (ParaView: Save Data, "
                                 "Data Mode Ascii)");
  }
  std::vector<T> v;
  Tokens t(a.body, file);
  while (!t.done()) {
    if constexpr (std::is_floating_point_v<T>) {
      v.push_back(t.real(what));
    } else {
      v.push_back(t.integer(what));
    }
  }
  return v;
}

RawMesh read_vtu(const std::string& text, const std::string& file) {
  RawMesh m;
  m.format = "vtu";
  const auto vf = text.find("<VTKFile");
  if (vf == std::string::npos) throw InputError(file, "VTKFile", "not a VTK XML file");
  const std::string vtk_tag = text.substr(vf, text.find('>', vf) - vf);
  if (attribute(vtk_tag, "type") != "UnstructuredGrid") {
    throw InputError(file, "VTKFile type", "'" + attribute(vtk_tag, "type") + "': an UnstructuredGrid is needed");
  }
  if (!attribute(vtk_tag, "compressor").empty()) throw InputError(file, "VTKFile compressor", "compressed files are not read");
  if (text.find("<Piece", text.find("<Piece") + 1) != std::string::npos) throw InputError(file, "Piece", "several pieces are not read");
  const auto points = arrays_in(text, "Points", file);
  if (points.size() != 1) throw InputError(file, "Points", "expected one DataArray");
  m.nodes = ascii_values<double>(points[0], file, "Points");
  if (m.nodes.size() % 3 != 0) throw InputError(file, "Points", "not a multiple of 3 values");
  std::vector<int64_t> connectivity, offsets, types;
  for (const auto& a : arrays_in(text, "Cells", file)) {
    const std::string name = attribute(a.tag, "Name");
    if (name == "connectivity") connectivity = ascii_values<int64_t>(a, file, "Cells/connectivity");
    if (name == "offsets") offsets = ascii_values<int64_t>(a, file, "Cells/offsets");
    if (name == "types") types = ascii_values<int64_t>(a, file, "Cells/types");
  }
  if (offsets.size() != types.size()) throw InputError(file, "Cells/offsets", "not one offset per cell type");
  const std::vector<XmlArray> cell_data = arrays_in(text, "CellData", file);
  std::vector<int64_t> labels;
  for (const char* wanted : {"labels", "label", "gmsh:physical", "medit:ref", "CellEntityIds"}) {
    for (const auto& a : cell_data) {
      if (labels.empty() && attribute(a.tag, "Name") == wanted) labels = ascii_values<int64_t>(a, file, std::string("CellData/") + wanted);
    }
  }
  m.labels_from_file = !labels.empty();
  if (!labels.empty() && labels.size() != types.size()) throw InputError(file, "CellData", "the label array has not one value per cell");
  int64_t begin = 0;
  for (std::size_t c = 0; c < types.size(); ++c) {
    const int64_t end = offsets[c];
    if (end < begin || end > static_cast<int64_t>(connectivity.size())) {
      throw InputError(file, "Cells/offsets", fmt::format("cell {}: offset {} out of range", c + 1, end));
    }
    if (types[c] == 10) {  // VTK_TETRA
      if (end - begin != 4) throw InputError(file, "Cells", fmt::format("cell {}: a VTK_TETRA with {} nodes", c + 1, end - begin));
      for (int64_t i = begin; i < end; ++i) m.tets.push_back(connectivity[static_cast<std::size_t>(i)]);
      m.labels.push_back(labels.empty() ? 1 : labels[c]);
    } else {
      ++m.skipped;
    }
    begin = end;
  }
  return m;
}

}  // namespace

// The formats ctsurg writes are the ones it reads back (tet_mesh_export.h).
std::string tet_mesh_import_format(const std::filesystem::path& path) { return tet_mesh_export_format(path); }

void compute_boundary_faces(TetMesh& mesh) {
  // Face (sorted triple) -> first (tet, local face), and how many tets hold it.
  struct Holder {
    int64_t tet = -1, other = -1;
    int local = 0;
  };
  std::map<std::array<int32_t, 3>, Holder> faces;
  static constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};  // outward for a positive tet
  std::vector<std::array<int32_t, 3>> order;
  const int64_t nt = mesh.tet_count();
  for (int64_t t = 0; t < nt; ++t) {
    const int32_t* c = &mesh.tets[static_cast<std::size_t>(4 * t)];
    for (int f = 0; f < 4; ++f) {
      std::array<int32_t, 3> key{c[kFace[f][0]], c[kFace[f][1]], c[kFace[f][2]]};
      std::sort(key.begin(), key.end());
      auto [it, fresh] = faces.try_emplace(key, Holder{t, -1, f});
      if (fresh) {
        order.push_back(key);
      } else {
        it->second.other = t;
      }
    }
  }
  mesh.boundary_faces.clear();
  mesh.face_labels.clear();
  for (const auto& key : order) {
    const Holder& h = faces.at(key);
    int64_t t = h.tet;
    int local = h.local;
    uint16_t in = mesh.tet_labels[static_cast<std::size_t>(t)];
    uint16_t out = h.other >= 0 ? mesh.tet_labels[static_cast<std::size_t>(h.other)] : uint16_t{0};
    if (in == out) continue;
    if (out != 0 && out < in) {  // inside is the smaller label: take the face from the other tet
      t = h.other;
      std::swap(in, out);
      const int32_t* c = &mesh.tets[static_cast<std::size_t>(4 * t)];
      for (int f = 0; f < 4; ++f) {
        std::array<int32_t, 3> k2{c[kFace[f][0]], c[kFace[f][1]], c[kFace[f][2]]};
        std::sort(k2.begin(), k2.end());
        if (k2 == key) local = f;
      }
    }
    const int32_t* c = &mesh.tets[static_cast<std::size_t>(4 * t)];
    mesh.boundary_faces.insert(mesh.boundary_faces.end(), {c[kFace[local][0]], c[kFace[local][1]], c[kFace[local][2]]});
    mesh.face_labels.insert(mesh.face_labels.end(), {in, out});
  }
}

TetMeshImport import_tet_mesh(const std::filesystem::path& path) {
  const std::string file = path.string();
  const std::string format = tet_mesh_import_format(path);
  if (format.empty()) throw InputError(file, "suffix", "unknown tet mesh format; use .vtu, .msh or .mesh");
  check_input_file(path);
  const std::string text = read_import_file(path);
  RawMesh raw = format == "vtu" ? read_vtu(text, file) : format == "msh" ? read_gmsh(text, file) : read_medit(text, file);
  const int64_t nn = static_cast<int64_t>(raw.nodes.size() / 3), nt = static_cast<int64_t>(raw.tets.size() / 4);
  if (nt == 0) throw InputError(file, "tets", fmt::format("no 4-node tetrahedra ({} other cells)", raw.skipped));
  if (nn > std::numeric_limits<int32_t>::max()) throw InputError(file, "nodes", "more than 2^31 nodes");
  for (std::size_t i = 0; i < raw.nodes.size(); ++i) {
    if (!std::isfinite(raw.nodes[i])) throw InputError(file, fmt::format("node {}", i / 3 + 1), "coordinate not finite");
  }

  TetMeshImport r;
  r.format = raw.format;
  r.skipped_cells = raw.skipped;
  r.labels_from_file = raw.labels_from_file;
  TetMesh& m = r.mesh;
  const auto node = [&](int64_t v) {
    return Eigen::Vector3d(raw.nodes[static_cast<std::size_t>(3 * v)], raw.nodes[static_cast<std::size_t>(3 * v + 1)],
                           raw.nodes[static_cast<std::size_t>(3 * v + 2)]);
  };
  std::map<std::array<int64_t, 4>, int64_t> seen;
  std::vector<int32_t> tets;
  tets.reserve(raw.tets.size());
  for (int64_t t = 0; t < nt; ++t) {
    const std::string element = fmt::format("tet {}", t + 1);
    std::array<int64_t, 4> c{};
    for (int a = 0; a < 4; ++a) {
      c[static_cast<std::size_t>(a)] = raw.tets[static_cast<std::size_t>(4 * t + a)];
      if (c[static_cast<std::size_t>(a)] < 0 || c[static_cast<std::size_t>(a)] >= nn) {
        throw InputError(file, element, fmt::format("node index {} out of range [1, {}] (1-based)", c[static_cast<std::size_t>(a)] + 1, nn));
      }
    }
    const int64_t label = raw.labels[static_cast<std::size_t>(t)];
    if (label < 1 || label > 65535) throw InputError(file, element, fmt::format("label {} is not in [1, 65535]", label));
    std::array<int64_t, 4> key = c;
    std::sort(key.begin(), key.end());
    if (std::adjacent_find(key.begin(), key.end()) != key.end()) throw InputError(file, element, "a node appears twice (degenerate)");
    if (const auto [it, fresh] = seen.try_emplace(key, t); !fresh) {
      throw InputError(file, element, fmt::format("the same four nodes as tet {} (duplicate element)", it->second + 1));
    }
    const Eigen::Vector3d p0 = node(c[0]), p1 = node(c[1]), p2 = node(c[2]), p3 = node(c[3]);
    const double v6 = 6.0 * tet_signed_volume(p0, p1, p2, p3);
    double l = 0.0;
    for (const auto& e : {p1 - p0, p2 - p0, p3 - p0, p2 - p1, p3 - p1, p3 - p2}) l = std::max(l, e.norm());
    if (!(std::abs(v6) > 1e-12 * l * l * l)) {
      throw InputError(file, element, fmt::format("zero volume (degenerate: {:.3g} mm^3, longest edge {:.3g} mm)", v6 / 6.0, l));
    }
    if (v6 < 0.0) {
      std::swap(c[2], c[3]);
      ++r.flipped;
    }
    for (const int64_t v : c) tets.push_back(static_cast<int32_t>(v));
    m.tet_labels.push_back(static_cast<uint16_t>(label));
  }
  // Keep only used nodes, in order of first use by the file's node order.
  std::vector<int32_t> renumber(static_cast<std::size_t>(nn), -1);
  for (const int32_t v : tets) renumber[static_cast<std::size_t>(v)] = 0;
  int32_t next = 0;
  for (int64_t v = 0; v < nn; ++v) {
    if (renumber[static_cast<std::size_t>(v)] < 0) {
      ++r.unused_nodes;
      continue;
    }
    renumber[static_cast<std::size_t>(v)] = next++;
    const Eigen::Vector3d p = node(v);
    m.nodes.insert(m.nodes.end(), {p[0], p[1], p[2]});
  }
  m.tets.reserve(tets.size());
  for (const int32_t v : tets) m.tets.push_back(renumber[static_cast<std::size_t>(v)]);
  compute_boundary_faces(m);
  m.quality = tet_mesh_quality(m.nodes, m.tets);
  m.mask_volume_mm3 = m.quality.volume_mm3;  // no mask: the mesh's own volume
  m.criteria = nlohmann::json{{"imported_from", path.filename().string()}, {"format", r.format}}.dump();
  validate_tet_mesh(m, file);
  return r;
}

}  // namespace ctsurg
