#include "ctsurg/preprocess/slicer_segmentation.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/input_file.h"
#include "ctsurg/core/memory_guard.h"
#include "header_text.h"

#include <spdlog/fmt/fmt.h>
#include <zlib.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <limits>
#include <regex>
#include <set>
#include <sstream>

namespace ctsurg {

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

std::vector<std::string> words(const std::string& s) {
  std::istringstream in(s);
  std::vector<std::string> w;
  for (std::string t; in >> t;) w.push_back(t);
  return w;
}

// The NRRD header (teem's NRRD0001..NRRD0005 format, "teem.sourceforge.net/nrrd/format.html"):
// "field: value" lines and "key:=value" pairs up to the blank line before attached data.
struct NrrdHeader {
  std::map<std::string, std::string> fields;     // lower-case field name -> value
  std::map<std::string, std::string> key_values; // key -> value, as written
  std::size_t data_offset = 0;                   // first byte after the blank line
};

NrrdHeader parse_seg_header(const std::string& bytes, const std::string& file) {
  if (bytes.compare(0, 4, "NRRD") != 0) throw InputError(file, "magic", "not a NRRD file (no NRRD000x first line)");
  NrrdHeader h;
  std::size_t at = bytes.find('\n');
  if (at == std::string::npos) throw InputError(file, "header", "no line after the magic");
  ++at;
  constexpr std::size_t kMaxHeader = 1 << 20;
  while (true) {
    if (at >= bytes.size()) throw InputError(file, "header", "ends without the blank line before the data");
    if (at > kMaxHeader) throw InputError(file, "header", "longer than 1 MiB");
    std::size_t end = bytes.find('\n', at);
    if (end == std::string::npos) end = bytes.size();
    std::string line = bytes.substr(at, end - at);
    at = end + 1;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) break;
    if (line[0] == '#') continue;
    const auto kv = line.find(":=");
    const auto colon = line.find(": ");
    if (kv != std::string::npos && (colon == std::string::npos || kv < colon)) {
      h.key_values[line.substr(0, kv)] = line.substr(kv + 2);
    } else if (colon != std::string::npos) {
      h.fields[lower(trim_header_text(line.substr(0, colon)))] = trim_header_text(line.substr(colon + 2));
    } else {
      throw InputError(file, "header", "'" + line.substr(0, 80) + "' is neither 'field: value' nor 'key:=value'");
    }
  }
  h.data_offset = std::min(at, bytes.size());
  return h;
}

const std::string& required(const NrrdHeader& h, const std::string& field, const std::string& file) {
  const auto it = h.fields.find(field);
  if (it == h.fields.end()) throw InputError(file, field, "missing");
  return it->second;
}

int64_t parse_int(const std::string& text, const std::string& file, const std::string& field) {
  try {
    std::size_t used = 0;
    const long long v = std::stoll(text, &used);
    if (used == text.size()) return v;
  } catch (const std::exception&) {
  }
  throw InputError(file, field, "'" + text + "' is not a whole number");
}

double parse_double(const std::string& text, const std::string& file, const std::string& field) {
  try {
    std::size_t used = 0;
    const double v = std::stod(text, &used);
    if (used == text.size() && std::isfinite(v)) return v;
  } catch (const std::exception&) {
  }
  throw InputError(file, field, "'" + text + "' is not a finite number");
}

// "(x,y,z)" -> vector.
Eigen::Vector3d parse_vector(const std::string& text, const std::string& file, const std::string& field) {
  std::string t = trim_header_text(text);
  if (t.size() < 2 || t.front() != '(' || t.back() != ')') throw InputError(file, field, "'" + t + "' is not a vector (x,y,z)");
  t = t.substr(1, t.size() - 2);
  std::vector<std::string> parts;
  std::stringstream in(t);
  for (std::string p; std::getline(in, p, ',');) parts.push_back(trim_header_text(p));
  if (parts.size() != 3) throw InputError(file, field, "'" + text + "' does not have 3 components");
  return {parse_double(parts[0], file, field), parse_double(parts[1], file, field), parse_double(parts[2], file, field)};
}

struct NrrdType {
  int bytes = 0;
  bool is_signed = false;
};

NrrdType nrrd_type(const std::string& type, const std::string& file) {
  const std::string t = lower(type);
  if (t == "uchar" || t == "unsigned char" || t == "uint8" || t == "uint8_t") return {1, false};
  if (t == "signed char" || t == "int8" || t == "int8_t") return {1, true};
  if (t == "short" || t == "short int" || t == "signed short" || t == "signed short int" || t == "int16" || t == "int16_t")
    return {2, true};
  if (t == "ushort" || t == "unsigned short" || t == "unsigned short int" || t == "uint16" || t == "uint16_t")
    return {2, false};
  if (t == "int" || t == "signed int" || t == "int32" || t == "int32_t") return {4, true};
  if (t == "uint" || t == "unsigned int" || t == "uint32" || t == "uint32_t") return {4, false};
  throw InputError(file, "type", "'" + type + "' is not an integer label type of 1 to 4 bytes");
}

std::string inflate_gzip(const std::string& in, std::size_t offset, std::size_t expected, const std::string& file) {
  std::string out(expected, '\0');
  z_stream z{};
  if (inflateInit2(&z, 15 + 32) != Z_OK) throw RuntimeError(file + ": zlib initialisation failed");
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(in.data() + offset));
  z.avail_in = static_cast<uInt>(std::min<std::size_t>(in.size() - offset, std::numeric_limits<uInt>::max()));
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = static_cast<uInt>(std::min<std::size_t>(expected, std::numeric_limits<uInt>::max()));
  int rc = Z_OK;
  while (rc == Z_OK && z.avail_out > 0) rc = inflate(&z, Z_NO_FLUSH);
  const std::size_t got = expected - z.avail_out;
  inflateEnd(&z);
  if (rc != Z_OK && rc != Z_STREAM_END) {
    throw InputError(file, "data", fmt::format("gzip data is damaged after {} of {} bytes ({})", got, expected,
                                               z.msg ? z.msg : "zlib error"));
  }
  if (got < expected) throw InputError(file, "data", fmt::format("gzip data ends after {} of {} bytes", got, expected));
  return out;
}

int64_t decode_value(const unsigned char* p, const NrrdType& t, bool big_endian) {
  uint32_t u = 0;
  for (int b = 0; b < t.bytes; ++b) {
    const int shift = 8 * (big_endian ? t.bytes - 1 - b : b);
    u |= static_cast<uint32_t>(p[b]) << shift;
  }
  if (!t.is_signed) return static_cast<int64_t>(u);
  const int bits = 8 * t.bytes;
  if (bits < 32 && (u >> (bits - 1)) & 1u) return static_cast<int64_t>(u) - (int64_t{1} << bits);
  return static_cast<int64_t>(static_cast<int32_t>(u));
}

std::string field_of(int k, const char* what) { return fmt::format("Segment{}_{}", k, what); }

}  // namespace

std::map<uint16_t, std::string> SlicerSegmentation::label_names() const {
  std::map<uint16_t, std::string> names;
  for (const auto& s : segments) names[s.label] = s.name;
  return names;
}

bool is_slicer_segmentation_file(const std::filesystem::path& path) {
  const std::string name = lower(path.filename().string());
  return name.size() > 9 && name.compare(name.size() - 9, 9, ".seg.nrrd") == 0;
}

SlicerSegmentation read_slicer_segmentation(const std::filesystem::path& path, std::vector<std::string>* warnings) {
  const std::string file = path.string();
  check_input_file(path);
  std::string bytes;
  {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    if (!in && !in.eof()) throw RuntimeError(file + ": read failed");
    bytes = s.str();
  }
  const NrrdHeader h = parse_seg_header(bytes, file);
  if (h.fields.count("data file") || h.fields.count("datafile")) {
    throw InputError(file, "data file", "detached data is not supported for a .seg.nrrd (Slicer writes attached data)");
  }
  for (const char* f : {"line skip", "lineskip", "byte skip", "byteskip"}) {
    if (h.fields.count(f) && parse_int(h.fields.at(f), file, f) != 0) throw InputError(file, f, "must be 0 (or absent)");
  }
  const NrrdType type = nrrd_type(required(h, "type", file), file);
  const int64_t dimension = parse_int(required(h, "dimension", file), file, "dimension");
  if (dimension != 3 && dimension != 4) {
    throw InputError(file, "dimension", fmt::format("{}: a segmentation has 3 (one layer) or 4 (layers) axes", dimension));
  }
  const auto size_words = words(required(h, "sizes", file));
  if (static_cast<int64_t>(size_words.size()) != dimension) {
    throw InputError(file, "sizes", fmt::format("{} sizes for dimension {}", size_words.size(), dimension));
  }
  std::vector<int64_t> sizes;
  for (const auto& w : size_words) {
    sizes.push_back(parse_int(w, file, "sizes"));
    if (sizes.back() < 1) throw InputError(file, "sizes", "'" + w + "' is not a positive size");
  }
  const int64_t layers = dimension == 4 ? sizes[0] : 1;
  const int spatial0 = dimension == 4 ? 1 : 0;
  if (dimension == 4 && h.fields.count("kinds")) {
    const auto kinds = words(h.fields.at("kinds"));
    if (kinds.empty() || (kinds[0] != "list" && kinds[0] != "vector")) {
      throw InputError(file, "kinds", "the first of 4 axes must be the 'list' of layers, got '" + h.fields.at("kinds") + "'");
    }
  }
  if (layers > 65535) throw InputError(file, "sizes", fmt::format("{} layers", layers));

  // Geometry: "space directions" columns and "space origin", in LPS or RAS.
  const std::string space = lower(required(h, "space", file));
  bool ras = false;
  if (space == "right-anterior-superior" || space == "ras") {
    ras = true;
  } else if (space != "left-posterior-superior" && space != "lps") {
    throw InputError(file, "space", "'" + h.fields.at("space") + "': only left-posterior-superior and "
                                    "right-anterior-superior are supported");
  }
  const std::string& directions_text = required(h, "space directions", file);
  std::vector<std::string> dir_words;
  {
    // Vectors contain no blanks after parsing "(a,b,c)" groups or "none".
    std::string cur;
    int depth = 0;
    for (const char c : directions_text) {
      if (c == '(') ++depth;
      if (c == ')') --depth;
      if ((c == ' ' || c == '\t') && depth == 0) {
        if (!cur.empty()) dir_words.push_back(cur);
        cur.clear();
      } else {
        cur += c;
      }
    }
    if (!cur.empty()) dir_words.push_back(cur);
  }
  if (static_cast<int64_t>(dir_words.size()) != dimension) {
    throw InputError(file, "space directions", fmt::format("{} entries for dimension {}", dir_words.size(), dimension));
  }
  if (dimension == 4 && dir_words[0] != "none") {
    throw InputError(file, "space directions", "the list axis must have direction 'none', got '" + dir_words[0] + "'");
  }
  const Eigen::Vector3d flip = ras ? Eigen::Vector3d(-1.0, -1.0, 1.0) : Eigen::Vector3d(1.0, 1.0, 1.0);
  ImageGeometry g;
  for (int a = 0; a < 3; ++a) {
    const Eigen::Vector3d v = parse_vector(dir_words[static_cast<std::size_t>(spatial0 + a)], file, "space directions").cwiseProduct(flip);
    const double n = v.norm();
    if (!(n > 0.0)) throw InputError(file, "space directions", fmt::format("axis {} has zero length", a));
    g.spacing[a] = n;
    g.direction.col(a) = v / n;
    g.dims[static_cast<std::size_t>(a)] = sizes[static_cast<std::size_t>(spatial0 + a)];
  }
  g.origin = parse_vector(required(h, "space origin", file), file, "space origin").cwiseProduct(flip);
  g.validate(file);

  // Segments: every k in 0 .. max with ID, Name, LabelValue and Layer.
  static const std::regex segment_key(R"(Segment(\d+)_(\w+))");
  int max_index = -1;
  for (const auto& [key, value] : h.key_values) {
    std::smatch m;
    if (std::regex_match(key, m, segment_key)) {
      const long k = std::stol(m[1].str().substr(0, 6));
      if (k > 65535) throw InputError(file, key, "segment index over 65535");
      max_index = std::max(max_index, static_cast<int>(k));
    }
  }
  if (max_index < 0) throw InputError(file, "Segment0_ID", "no Segment<k>_ fields: not a Slicer segmentation");
  SlicerSegmentation seg;
  for (int k = 0; k <= max_index; ++k) {
    const auto get = [&](const char* what) -> const std::string& {
      const auto it = h.key_values.find(field_of(k, what));
      if (it == h.key_values.end()) {
        throw InputError(file, field_of(k, what), fmt::format("absent (segment {} of {})", k, max_index + 1));
      }
      return it->second;
    };
    SlicerSegment s;
    s.index = k;
    s.id = get("ID");
    s.name = get("Name");
    s.label_value = parse_int(trim_header_text(get("LabelValue")), file, field_of(k, "LabelValue"));
    const int64_t layer = parse_int(trim_header_text(get("Layer")), file, field_of(k, "Layer"));
    if (layer < 0 || layer >= layers) {
      throw InputError(file, field_of(k, "Layer"), fmt::format("{} is not a layer in [0, {}]", layer, layers - 1));
    }
    s.layer = static_cast<int>(layer);
    if (s.label_value < 1 || s.label_value > 65535) {
      throw InputError(file, field_of(k, "LabelValue"), fmt::format("{} is not a label in [1, 65535]", s.label_value));
    }
    if (const auto it = h.key_values.find(field_of(k, "Color")); it != h.key_values.end()) {
      const auto c = words(it->second);
      if (c.size() != 3) throw InputError(file, field_of(k, "Color"), "expected 3 numbers, got '" + it->second + "'");
      for (std::size_t a = 0; a < 3; ++a) s.color[a] = parse_double(c[a], file, field_of(k, "Color"));
    }
    if (const auto it = h.key_values.find(field_of(k, "Extent")); it != h.key_values.end()) {
      const auto e = words(it->second);
      if (e.size() != 6) throw InputError(file, field_of(k, "Extent"), "expected 6 whole numbers, got '" + it->second + "'");
      for (const auto& w : e) parse_int(w, file, field_of(k, "Extent"));
    }
    for (const auto& other : seg.segments) {
      if (other.layer == s.layer && other.label_value == s.label_value) {
        throw InputError(file, field_of(k, "LabelValue"),
                         fmt::format("{} is also the label value of Segment{} ('{}') in layer {}: two segments of one "
                                     "layer need different values",
                                     s.label_value, other.index, other.name, s.layer));
      }
    }
    seg.segments.push_back(s);
  }
  // Merged labels: the label value, or, when a segment of an earlier layer took it, the next free one.
  {
    std::set<int64_t> used;
    for (const auto& s : seg.segments) used.insert(s.label_value);
    std::set<int64_t> taken;
    for (auto& s : seg.segments) {
      int64_t label = s.label_value;
      if (taken.count(label)) {
        label = 1;
        while (used.count(label) || taken.count(label)) ++label;
        if (label > 65535) throw InputError(file, field_of(s.index, "LabelValue"), "no free label left to renumber it");
        if (warnings) {
          warnings->push_back(fmt::format("{}: Segment{} '{}' (layer {}) shares label value {} with a segment of "
                                          "another layer; it is label {} in the merged labels",
                                          file, s.index, s.name, s.layer, s.label_value, label));
        }
      }
      taken.insert(label);
      s.label = static_cast<uint16_t>(label);
    }
  }

  // Voxel data.
  const std::string encoding = lower(required(h, "encoding", file));
  const int64_t voxels = g.voxel_count();
  const uint64_t values = static_cast<uint64_t>(voxels) * static_cast<uint64_t>(layers);
  check_allocation(values, static_cast<uint64_t>(type.bytes) + sizeof(uint16_t), file, "sizes");
  bool big_endian = false;
  if (type.bytes > 1 && encoding != "ascii" && encoding != "text" && encoding != "txt") {
    const std::string endian = lower(required(h, "endian", file));
    if (endian != "little" && endian != "big") throw InputError(file, "endian", "'" + endian + "' is not little or big");
    big_endian = endian == "big";
  }
  std::vector<int64_t> raw;  // layers fastest, then i, j, k (the NRRD's order for list-first files)
  raw.reserve(static_cast<std::size_t>(values));
  const std::size_t need = static_cast<std::size_t>(values) * static_cast<std::size_t>(type.bytes);
  if (encoding == "raw" || encoding == "gzip" || encoding == "gz") {
    std::string data;
    if (encoding == "raw") {
      if (bytes.size() - h.data_offset < need) {
        throw InputError(file, "data", fmt::format("{} bytes of voxel data, sizes need {}", bytes.size() - h.data_offset, need));
      }
      if (bytes.size() - h.data_offset > need && warnings) {
        warnings->push_back(fmt::format("{}: {} bytes after the voxel data ignored", file, bytes.size() - h.data_offset - need));
      }
      data = bytes.substr(h.data_offset, need);
    } else {
      data = inflate_gzip(bytes, h.data_offset, need, file);
    }
    const auto* p = reinterpret_cast<const unsigned char*>(data.data());
    for (uint64_t n = 0; n < values; ++n) raw.push_back(decode_value(p + n * static_cast<uint64_t>(type.bytes), type, big_endian));
  } else if (encoding == "ascii" || encoding == "text" || encoding == "txt") {
    std::istringstream in(bytes.substr(h.data_offset));
    for (uint64_t n = 0; n < values; ++n) {
      long long v = 0;
      if (!(in >> v)) throw InputError(file, "data", fmt::format("{} of {} ascii values", n, values));
      raw.push_back(v);
    }
  } else {
    throw InputError(file, "encoding", "'" + encoding + "': supported are raw, gzip and ascii");
  }

  // Merge the layers; every non-zero value must be a segment's, and no voxel in two segments.
  std::vector<std::map<int64_t, const SlicerSegment*>> by_value(static_cast<std::size_t>(layers));
  for (const auto& s : seg.segments) by_value[static_cast<std::size_t>(s.layer)][s.label_value] = &s;
  seg.labels = Volume<uint16_t>(g, 0);
  std::map<std::pair<int, int>, int64_t> overlaps;  // (segment a, segment b) -> voxels
  for (int64_t v = 0; v < voxels; ++v) {
    const SlicerSegment* here = nullptr;
    for (int64_t l = 0; l < layers; ++l) {
      const int64_t value = raw[static_cast<std::size_t>(v * layers + l)];
      if (value == 0) continue;
      const auto& table = by_value[static_cast<std::size_t>(l)];
      const auto it = table.find(value);
      if (it == table.end()) {
        const int64_t i = v % g.dims[0], j = v / g.dims[0] % g.dims[1], k = v / (g.dims[0] * g.dims[1]);
        throw InputError(file, "data", fmt::format("voxel ({}, {}, {}) of layer {} has value {}, which is no segment's "
                                                   "Segment<k>_LabelValue in that layer",
                                                   i, j, k, l, value));
      }
      if (here) {
        ++overlaps[{here->index, it->second->index}];
      } else {
        here = it->second;
        seg.labels.voxels[static_cast<std::size_t>(v)] = here->label;
      }
    }
  }
  if (!overlaps.empty()) {
    int64_t total = 0;
    std::string pairs;
    for (const auto& [ab, n] : overlaps) {
      total += n;
      const auto& a = seg.segments[static_cast<std::size_t>(ab.first)];
      const auto& b = seg.segments[static_cast<std::size_t>(ab.second)];
      pairs += fmt::format("{}{} voxels in Segment{} '{}' and Segment{} '{}'", pairs.empty() ? "" : "; ", n, a.index,
                           a.name, b.index, b.name);
    }
    throw InputError(file, "Segment<k>_Layer",
                     fmt::format("the layers overlap: {} voxels lie in two segments ({}); ctsurg needs one tissue per "
                                 "voxel: remove the overlap in Slicer (e.g. Segment Editor, masking 'outside all segments')",
                                 total, pairs));
  }
  return seg;
}

Volume<uint16_t> place_on_lattice(const Volume<uint16_t>& seg, const ImageGeometry& ct, const std::string& file) {
  const ImageGeometry& g = seg.geometry;
  const auto describe = [](const ImageGeometry& x) {
    return fmt::format("{} x {} x {} voxels, spacing {:.6g} {:.6g} {:.6g} mm, origin {:.6g} {:.6g} {:.6g} mm", x.dims[0],
                       x.dims[1], x.dims[2], x.spacing[0], x.spacing[1], x.spacing[2], x.origin[0], x.origin[1],
                       x.origin[2]);
  };
  const std::string both = "segmentation " + describe(g) + "; CT " + describe(ct);
  // The index offset of the box, and the same axes: each box axis one CT voxel step along a CT axis.
  const Eigen::Vector3d offset = ct.world_to_index(g.origin);
  const Eigen::Vector3d rounded = offset.array().round();
  if ((ct.index_to_world(rounded) - g.origin).norm() > 1e-3) {
    throw InputError(file, "space origin", "not on a voxel centre of the CT: " + both);
  }
  const Eigen::Matrix3d a = g.index_to_world_matrix(), b = ct.index_to_world_matrix();
  const double extent = static_cast<double>(std::max({g.dims[0], g.dims[1], g.dims[2]}));
  if ((a - b).cwiseAbs().maxCoeff() * extent > 1e-3) {
    throw InputError(file, "space directions", "the voxel axes or spacing differ from the CT's: " + both);
  }
  Volume<uint16_t> out(ct, 0);
  int64_t outside = 0;
  const int64_t o0 = static_cast<int64_t>(rounded[0]), o1 = static_cast<int64_t>(rounded[1]),
                o2 = static_cast<int64_t>(rounded[2]);
  for (int64_t k = 0; k < g.dims[2]; ++k)
    for (int64_t j = 0; j < g.dims[1]; ++j)
      for (int64_t i = 0; i < g.dims[0]; ++i) {
        const uint16_t l = seg(i, j, k);
        if (!l) continue;
        const int64_t x = i + o0, y = j + o1, z = k + o2;
        if (x < 0 || y < 0 || z < 0 || x >= ct.dims[0] || y >= ct.dims[1] || z >= ct.dims[2]) {
          ++outside;
          continue;
        }
        out(x, y, z) = l;
      }
  if (outside > 0) {
    throw InputError(file, "sizes", fmt::format("{} labelled voxels lie outside the CT: {}", outside, both));
  }
  return out;
}

}  // namespace ctsurg
