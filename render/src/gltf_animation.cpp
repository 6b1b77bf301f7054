#include "ctsurg/render/gltf_animation.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <tuple>

#include "ctsurg/core/checked_write.h"
#include "ctsurg/core/error.h"
#include "ctsurg/core/progress_bar.h"
#include "ctsurg/core/version.h"
#include "ctsurg/mesh/gltf_frame.h"
#include "ctsurg/mesh/gltf_material.h"
#include "ctsurg/mesh/normal_map_png.h"
#include "ctsurg/render/deformed_tangent_frames.h"

namespace ctsurg {

namespace {

using nlohmann::json;

// glTF 2.0 enumerations: accessor.componentType (5.1.3), bufferView.target (5.11.4), sampler filters
// and wrapping (5.26).
constexpr int kUnsignedShort = 5123, kUnsignedInt = 5125, kFloat = 5126;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;
constexpr int kLinear = 9729, kLinearMipmapLinear = 9987, kClampToEdge = 33071;
constexpr int kTriangles = 4;

// The materials (mesh/gltf_material.h): tissue, as the static export has it, with the normal map;
// wound, the renderer's inside of a cut, matte, no normal map.
json tissue_material(bool with_map, bool cut) {
  json m = {{"name", cut ? "tissue (cut open)" : "tissue"},
            {"pbrMetallicRoughness",
             {{"baseColorFactor", gltf_linear_colour(kGltfTissueOnScreen)},
              {"metallicFactor", kGltfTissueMetallic},
              {"roughnessFactor", kGltfTissueRoughness}}}};
  if (with_map) m["normalTexture"] = {{"index", 0}};
  // A cut opens the surface: its inside must be drawn (glTF culls back faces unless doubleSided).
  if (cut) m["doubleSided"] = true;
  return m;
}
json wound_material() {
  return {{"name", "wound"},
          {"pbrMetallicRoughness",
           {{"baseColorFactor", gltf_linear_colour(kGltfWoundOnScreen)}, {"metallicFactor", 0.0}, {"roughnessFactor", kGltfWoundRoughness}}},
          {"doubleSided", true}};
}

const char* accessor_type(int width) { return width == 1 ? "SCALAR" : width == 2 ? "VEC2" : width == 3 ? "VEC3" : "VEC4"; }

// Per-component min and max of `count` elements of `width` floats (`zero`: a zero element counts too,
// as for a sparse accessor's untouched elements). Floats go to JSON as the doubles they are, so the
// validator's exact comparison with the data holds.
std::pair<json, json> float_bounds(const float* v, std::size_t count, int width, bool zero) {
  std::vector<float> lo(static_cast<std::size_t>(width), std::numeric_limits<float>::infinity());
  std::vector<float> hi(static_cast<std::size_t>(width), -std::numeric_limits<float>::infinity());
  if (zero) std::fill(lo.begin(), lo.end(), 0.0f), std::fill(hi.begin(), hi.end(), 0.0f);
  for (std::size_t e = 0; e < count; ++e)
    for (int c = 0; c < width; ++c) {
      lo[c] = std::min(lo[c], v[e * width + c]);
      hi[c] = std::max(hi[c], v[e * width + c]);
    }
  json mn = json::array(), mx = json::array();
  for (int c = 0; c < width; ++c) mn.push_back(static_cast<double>(lo[c] == 0.0f ? 0.0f : lo[c])), mx.push_back(static_cast<double>(hi[c] == 0.0f ? 0.0f : hi[c]));
  return {mn, mx};
}

// The binary buffer and the buffer views and accessors that point into it. Every view starts on a
// 4-byte boundary (glTF 2.0, 3.6.2.4: an accessor's offset is a multiple of its component size, and
// vertex attributes of 4).
class BinaryBuffer {
 public:
  std::string bin;
  json views = json::array(), accessors = json::array();

  // A new view of `bytes` (> 0) bytes; `target` 0 for none (animation data, sparse arrays, images).
  std::size_t add_view(const void* data, std::size_t bytes, int target) {
    while (bin.size() % 4 != 0) bin.push_back('\0');
    json v = {{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", bytes}};
    if (target != 0) v["target"] = target;
    bin.append(static_cast<const char*>(data), bytes);
    views.push_back(std::move(v));
    return views.size() - 1;
  }
  std::size_t add_accessor(json a) {
    accessors.push_back(std::move(a));
    return accessors.size() - 1;
  }
  // A tightly packed float accessor of values.size() / width elements, with min/max when `bounds`.
  std::size_t add_floats(const std::vector<float>& values, int width, int target, bool bounds) {
    const std::size_t count = values.size() / static_cast<std::size_t>(width);
    json a = {{"bufferView", add_view(values.data(), values.size() * sizeof(float), target)},
              {"componentType", kFloat},
              {"count", count},
              {"type", accessor_type(width)}};
    if (bounds) std::tie(a["min"], a["max"]) = float_bounds(values.data(), count, width, false);
    return add_accessor(std::move(a));
  }
  // Triangle indices (`count` values), unsigned short when every vertex id fits below 65535 (the
  // primitive restart value, which glTF forbids as an index), else unsigned int.
  std::size_t add_indices(const uint32_t* indices, std::size_t count, bool short_indices) {
    std::size_t view = 0;
    if (short_indices) {
      std::vector<uint16_t> s(indices, indices + count);
      view = add_view(s.data(), s.size() * sizeof(uint16_t), kElementArrayBuffer);
    } else {
      view = add_view(indices, count * sizeof(uint32_t), kElementArrayBuffer);
    }
    return add_accessor({{"bufferView", view}, {"componentType", short_indices ? kUnsignedShort : kUnsignedInt},
                         {"count", count}, {"type", "SCALAR"}});
  }
  // A morph target's #V x 3 deltas, stored as the smallest of: no data (every delta zero: glTF
  // initialises an accessor without a buffer view to zeros, 3.6.2.1), sparse (the moved vertices'
  // ids and deltas, 3.6.2.3) or dense. `sparse` counts the first two.
  std::size_t add_target(const std::vector<float>& d, bool bounds, int64_t& sparse) {
    const std::size_t nv = d.size() / 3;
    std::vector<uint32_t> moved;
    for (std::size_t v = 0; v < nv; ++v)
      if (d[3 * v] != 0.0f || d[3 * v + 1] != 0.0f || d[3 * v + 2] != 0.0f) moved.push_back(static_cast<uint32_t>(v));
    json a = {{"componentType", kFloat}, {"count", nv}, {"type", "VEC3"}};
    const bool short_ids = nv <= 65536;
    const std::size_t id_bytes = short_ids ? 2 : 4;
    if (moved.empty()) {
      ++sparse;
      if (bounds) a["min"] = a["max"] = json::array({0.0, 0.0, 0.0});
      return add_accessor(std::move(a));
    }
    if (moved.size() * (12 + id_bytes) < nv * 12) {
      ++sparse;
      std::vector<float> values(3 * moved.size());
      for (std::size_t k = 0; k < moved.size(); ++k) std::copy_n(&d[3 * moved[k]], 3, &values[3 * k]);
      std::size_t ids = 0;
      if (short_ids) {
        const std::vector<uint16_t> s(moved.begin(), moved.end());
        ids = add_view(s.data(), s.size() * 2, 0);
      } else {
        ids = add_view(moved.data(), moved.size() * 4, 0);
      }
      const std::size_t vals = add_view(values.data(), values.size() * sizeof(float), 0);
      a["sparse"] = {{"count", moved.size()},
                     {"indices", {{"bufferView", ids}, {"componentType", short_ids ? kUnsignedShort : kUnsignedInt}}},
                     {"values", {{"bufferView", vals}}}};
      if (bounds) std::tie(a["min"], a["max"]) = float_bounds(values.data(), moved.size(), 3, moved.size() < nv);
      return add_accessor(std::move(a));
    }
    a["bufferView"] = add_view(d.data(), d.size() * sizeof(float), kArrayBuffer);
    if (bounds) std::tie(a["min"], a["max"]) = float_bounds(d.data(), nv, 3, false);
    return add_accessor(std::move(a));
  }
};

// One exported frame: what it draws.
struct ExportFrame {
  const float* vertices;                   // #V x 3, LPS mm
  const std::vector<uint32_t>* triangles;  // its topology's triangles
  int topology;                            // the topology's id (-1: the surface file's own)
  int64_t closing;                         // its last `closing` triangles close cut holes
  int64_t index;                           // the trajectory frame (-1: the surface)
  double time_s;                           // simulated time
};

// A run of consecutive exported frames [first, last] with one topology: one node and mesh.
struct Run {
  std::size_t first, last;
};

// Percent-encoding of a file name for a URI (RFC 3986: unreserved characters kept).
std::string uri_encode(const std::string& name) {
  static const char* hex = "0123456789ABCDEF";
  std::string out;
  for (const unsigned char c : name) {
    if (std::isalnum(c) || c == '-' || c == '.' || c == '_' || c == '~') {
      out.push_back(static_cast<char>(c));
    } else {
      out += '%';
      out += hex[c >> 4];
      out += hex[c & 15];
    }
  }
  return out;
}

void append_gltf_u32(std::string& s, uint32_t v) { s.append(reinterpret_cast<const char*>(&v), 4); }

}  // namespace

std::string gltf_animation_format(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".glb" ? "glb" : ext == ".gltf" ? "gltf" : "";
}

std::vector<std::filesystem::path> gltf_animation_files(const std::filesystem::path& output) {
  std::vector<std::filesystem::path> files{output};
  if (gltf_animation_format(output) == "gltf") files.push_back(std::filesystem::path(output).replace_extension(".bin"));
  return files;
}

std::vector<std::pair<std::string, std::string>> export_gltf_animation(const std::filesystem::path& output,
                                                                       const SurfaceMesh& surface,
                                                                       const Trajectory* trajectory,
                                                                       const GltfAnimationOptions& options,
                                                                       GltfAnimationSummary* summary) {
  const std::string format = gltf_animation_format(output);
  if (format.empty()) {
    throw InputError(output.string(), "suffix", "an animated glTF is .glb (binary) or .gltf (JSON with a .bin beside it)");
  }
  if (!(std::isfinite(options.time_scale) && options.time_scale > 0.0)) {
    throw InputError("--time-scale", "", "must be a finite number > 0, got " + std::to_string(options.time_scale));
  }
  const std::string tname = options.trajectory_name.empty() ? std::string("trajectory") : options.trajectory_name;
  const int64_t nv = surface.vertex_count();
  if (nv == 0 || surface.triangle_count() == 0) throw InputError(output.string(), "surface", "the mesh is empty");

  // The exported frames.
  std::vector<ExportFrame> frames;
  if (!trajectory) {
    frames.push_back({surface.vertices.data(), &surface.triangles, -1, 0, -1, 0.0});
  } else {
    if (trajectory->vertex_count() != nv) {
      throw InputError(tname, "/trajectory/surface/rest_vertices",
                       std::to_string(trajectory->vertex_count()) + " vertices, but the surface has " + std::to_string(nv) +
                           ": the trajectory was simulated with another surface");
    }
    const int64_t f_count = trajectory->frame_count();
    std::vector<int64_t> list = options.frames;
    if (list.empty()) {
      if (f_count == 0) throw InputError(tname, "/trajectory/time", "no frames");
      for (int64_t f = 0; f < f_count; ++f) list.push_back(f);
    }
    for (std::size_t i = 0; i < list.size(); ++i) {
      const int64_t f = list[i];
      if (f < 0 || f >= f_count) {
        throw InputError(tname, "frames", "frame " + std::to_string(f) + " is out of range 0.." + std::to_string(f_count - 1));
      }
      if (i > 0 && f <= list[i - 1]) throw InputError(tname, "frames", "frames must be ascending and unique");
      const int k = trajectory->topology_of_frame[static_cast<std::size_t>(f)];
      const auto& triangles = trajectory->topologies[static_cast<std::size_t>(k)];
      if (triangles.empty()) {
        throw InputError(tname, "/trajectory/surface/topologies/" + std::to_string(k),
                         "frame " + std::to_string(f) + " draws no triangles: nothing to export");
      }
      const int64_t closing = trajectory->closing_triangles.empty() ? 0 : trajectory->closing_triangles[static_cast<std::size_t>(k)];
      frames.push_back({trajectory->frame_vertices(f), &triangles, k,
                        std::clamp<int64_t>(closing, 0, static_cast<int64_t>(triangles.size() / 3)), f,
                        trajectory->time[static_cast<std::size_t>(f)]});
    }
  }
  const std::size_t n = frames.size();
  // Key times, seconds from the first exported frame; glTF keys must increase strictly (as float32).
  std::vector<float> key_time(n);
  for (std::size_t i = 0; i < n; ++i) {
    key_time[i] = static_cast<float>((frames[i].time_s - frames[0].time_s) * options.time_scale);
    if (i > 0 && !(key_time[i] > key_time[i - 1])) {
      throw InputError(tname, "/trajectory/time",
                       "frames " + std::to_string(frames[i - 1].index) + " and " + std::to_string(frames[i].index) +
                           " have the same time (" + std::to_string(frames[i].time_s) +
                           " s, as float32 seconds): glTF animation keys must increase");
    }
  }
  std::vector<Run> runs;
  for (std::size_t i = 0; i < n; ++i) {
    if (runs.empty() || frames[i].topology != frames[runs.back().first].topology) runs.push_back({i, i});
    runs.back().last = i;
  }

  const bool with_map = options.normal_map && !surface.normal_map.empty() && !surface.uvs.empty() && !surface.tangents.empty();
  const bool short_indices = nv <= 65535;
  BinaryBuffer b;
  json j;
  j["asset"] = {{"version", "2.0"}, {"generator", std::string("ctsurg ") + kVersion}, {"extras", {{"ctsurg_frame", kGltfFrameNote}}}};
  if (with_map) {
    // The map first (as the static export): a PNG in the buffer, sampled linearly, clamped at the atlas's edge.
    const std::vector<uint8_t> png = encode_normal_map_png(surface.normal_map);
    j["images"] = json::array({{{"bufferView", b.add_view(png.data(), png.size(), 0)}, {"mimeType", "image/png"}, {"name", "normal_map"}}});
    j["samplers"] = json::array({{{"magFilter", kLinear}, {"minFilter", kLinearMipmapLinear}, {"wrapS", kClampToEdge}, {"wrapT", kClampToEdge}}});
    j["textures"] = json::array({{{"sampler", 0}, {"source", 0}}});
  }

  // The base's bounding-box centre (glTF frame, metres): every node is translated there and positions
  // are stored relative to it, so a node scaled to 0 (hidden) collapses inside the model, not onto the
  // origin far away, where viewers framing the scene's bounds would include it.
  std::array<float, 3> centre{};
  {
    std::array<float, 3> lo, hi;
    lo.fill(std::numeric_limits<float>::infinity());
    hi.fill(-std::numeric_limits<float>::infinity());
    for (int64_t v = 0; v < nv; ++v) {
      const auto q = lps_mm_to_gltf_position(&frames[0].vertices[3 * v]);
      for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], q[c]), hi[c] = std::max(hi[c], q[c]);
    }
    for (int c = 0; c < 3; ++c) centre[c] = static_cast<float>(0.5 * (double(lo[c]) + double(hi[c])));
  }
  // Frame i in the glTF frame: positions (metres, from the centre), normals and tangents rotated
  // (deformed with the tissue).
  DeformedTangentFrames tangent_frames(surface);
  std::vector<float> lps_normals, lps_tangents;
  const auto to_gltf = [&](const ExportFrame& f, std::vector<float>& p, std::vector<float>& nrm, std::vector<float>* tan) {
    // A frame at rest keeps the file's frames bit for bit (as the static export has them; the rotation
    // computed from identical frames is the identity only to rounding).
    const bool at_rest = *f.triangles == surface.triangles &&
                         std::equal(surface.vertices.begin(), surface.vertices.end(), f.vertices);
    if (at_rest) {
      lps_normals = surface.normals;
      lps_tangents = surface.tangents;
    } else {
      tangent_frames.compute(f.vertices, *f.triangles, f.topology, lps_normals, lps_tangents);
    }
    p.resize(3 * static_cast<std::size_t>(nv));
    nrm.resize(3 * static_cast<std::size_t>(nv));
    for (std::size_t v = 0; v < static_cast<std::size_t>(nv); ++v) {
      const auto q = lps_mm_to_gltf_position(&f.vertices[3 * v]);
      const auto m = lps_to_gltf_direction(&lps_normals[3 * v]);
      for (int c = 0; c < 3; ++c) p[3 * v + c] = q[c] - centre[c];
      std::copy(m.begin(), m.end(), &nrm[3 * v]);
    }
    if (tan) {
      tan->resize(4 * static_cast<std::size_t>(nv));
      for (std::size_t v = 0; v < static_cast<std::size_t>(nv); ++v) {
        const auto t = lps_to_gltf_direction(&lps_tangents[4 * v]);
        std::copy(t.begin(), t.end(), &(*tan)[4 * v]);
        (*tan)[4 * v + 3] = lps_tangents[4 * v + 3];  // a proper rotation keeps the handedness
      }
    }
  };

  ProgressBar bar("exporting glTF", n);
  // The base: frame 0's attributes, shared by every mesh.
  std::vector<float> base_p, base_n, base_t;
  to_gltf(frames[0], base_p, base_n, with_map ? &base_t : nullptr);
  bar.advance();
  json attributes = {{"POSITION", b.add_floats(base_p, 3, kArrayBuffer, true)}, {"NORMAL", b.add_floats(base_n, 3, kArrayBuffer, false)}};
  if (with_map) {
    attributes["TANGENT"] = b.add_floats(base_t, 4, kArrayBuffer, false);
    // ctsurg's uvs already follow glTF (v down the image from its top row).
    attributes["TEXCOORD_0"] = b.add_floats(surface.uvs, 2, kArrayBuffer, false);
  }
  // Triangles per topology (tissue, closing), once each even when a topology comes back.
  std::map<int, std::pair<int64_t, int64_t>> index_accessors;
  for (const Run& r : runs) {
    const ExportFrame& f = frames[r.first];
    if (index_accessors.count(f.topology)) continue;
    const std::size_t tissue = f.triangles->size() / 3 - static_cast<std::size_t>(f.closing);
    const int64_t a = tissue ? static_cast<int64_t>(b.add_indices(f.triangles->data(), 3 * tissue, short_indices)) : -1;
    const int64_t c = f.closing ? static_cast<int64_t>(b.add_indices(f.triangles->data() + 3 * tissue, 3 * static_cast<std::size_t>(f.closing), short_indices)) : -1;
    index_accessors[f.topology] = {a, c};
  }
  // Morph targets, frame by frame: frame i minus the base.
  GltfAnimationSummary s;
  s.frames = static_cast<int64_t>(n);
  std::vector<std::size_t> target_position(n), target_normal(n);
  {
    std::vector<float> p, nrm;
    for (std::size_t i = 1; i < n; ++i) {
      to_gltf(frames[i], p, nrm, nullptr);
      for (std::size_t k = 0; k < p.size(); ++k) p[k] -= base_p[k], nrm[k] -= base_n[k];
      target_position[i] = b.add_target(p, true, s.sparse_targets);
      target_normal[i] = b.add_target(nrm, false, s.sparse_targets);
      ++s.morph_targets;
      bar.advance();
    }
  }

  // Materials (only those used), meshes and nodes: one per run.
  json materials = json::array(), meshes = json::array(), nodes = json::array();
  std::map<std::string, std::size_t> material_index;
  const auto material = [&](const json& m) {
    const std::string name = m.at("name").get<std::string>();
    if (!material_index.count(name)) material_index[name] = materials.size(), materials.push_back(m);
    return material_index[name];
  };
  std::vector<std::vector<std::size_t>> run_targets(runs.size());  // exported frame indices with a target
  for (std::size_t r = 0; r < runs.size(); ++r) {
    const ExportFrame& f = frames[runs[r].first];
    const bool cut = f.topology != frames[0].topology;
    json targets = json::array(), names = json::array();
    for (std::size_t i = runs[r].first; i <= runs[r].last; ++i) {
      if (i == 0) continue;  // the base itself
      run_targets[r].push_back(i);
      targets.push_back({{"POSITION", target_position[i]}, {"NORMAL", target_normal[i]}});
      names.push_back("frame " + std::to_string(frames[i].index));
    }
    json primitives = json::array();
    const auto [tissue, closing] = index_accessors.at(f.topology);
    if (tissue >= 0) primitives.push_back({{"attributes", attributes}, {"indices", tissue}, {"material", material(tissue_material(with_map, cut))}, {"mode", kTriangles}});
    if (closing >= 0) {
      // No normal map on the wound: its primitive leaves the texture coordinates and tangents out.
      const json plain = {{"POSITION", attributes.at("POSITION")}, {"NORMAL", attributes.at("NORMAL")}};
      primitives.push_back({{"attributes", plain}, {"indices", closing}, {"material", material(wound_material())}, {"mode", kTriangles}});
    }
    json mesh = {{"name", "surface"}, {"primitives", primitives}};
    if (!targets.empty()) {
      for (auto& p : mesh["primitives"]) p["targets"] = targets;
      mesh["weights"] = std::vector<double>(targets.size(), 0.0);
      mesh["extras"] = {{"targetNames", names}};  // the convention three.js and Blender read
    }
    meshes.push_back(mesh);
    json node = {{"mesh", r}, {"translation", {double(centre[0]), double(centre[1]), double(centre[2])}}};
    if (runs.size() == 1) {
      node["name"] = "surface";
    } else {
      node["name"] = "surface, frames " + std::to_string(frames[runs[r].first].index) + " to " + std::to_string(frames[runs[r].last].index);
      node["extras"] = {{"ctsurg_topology", f.topology}};
      if (r > 0) node["scale"] = {0.0, 0.0, 0.0};  // hidden until its first frame
    }
    nodes.push_back(node);
  }
  s.nodes = static_cast<int64_t>(runs.size());
  j["materials"] = materials;
  j["meshes"] = meshes;
  j["nodes"] = nodes;
  j["scenes"] = json::array({{{"nodes", [&] {
                                 json all = json::array();
                                 for (std::size_t r = 0; r < runs.size(); ++r) all.push_back(r);
                                 return all;
                               }()}}});
  j["scene"] = 0;

  // The animation: per run, its morph weights (LINEAR, one-hot at its keys) and, with several runs,
  // its visibility (scale, STEP).
  if (n > 1) {
    json samplers = json::array(), channels = json::array();
    const auto add_sampler = [&](const std::vector<float>& keys, const std::vector<float>& values, int width,
                                 const char* interpolation, std::size_t node, const char* path) {
      json in = {{"bufferView", b.add_view(keys.data(), keys.size() * sizeof(float), 0)}, {"componentType", kFloat},
                 {"count", keys.size()}, {"type", "SCALAR"}};
      std::tie(in["min"], in["max"]) = float_bounds(keys.data(), keys.size(), 1, false);
      const std::size_t out = b.add_accessor({{"bufferView", b.add_view(values.data(), values.size() * sizeof(float), 0)},
                                              {"componentType", kFloat}, {"count", values.size() / static_cast<std::size_t>(width)},
                                              {"type", accessor_type(width)}});
      samplers.push_back({{"input", b.add_accessor(std::move(in))}, {"output", out}, {"interpolation", interpolation}});
      channels.push_back({{"sampler", samplers.size() - 1}, {"target", {{"node", node}, {"path", path}}}});
    };
    // One more key, a frame interval after the last frame, holds it: a looping viewer shows the last
    // frame as long as the others (its clock wraps to 0 at the clip's end, where the last key is).
    const float hold_end = key_time[n - 1] + (key_time[n - 1] - key_time[n - 2]);
    const bool hold = hold_end > key_time[n - 1];
    for (std::size_t r = 0; r < runs.size(); ++r) {
      const std::vector<std::size_t>& targets = run_targets[r];
      const bool last_run = r + 1 == runs.size();
      if (!targets.empty()) {
        std::vector<float> times, weights;
        for (std::size_t i = runs[r].first; i <= runs[r].last; ++i) {
          times.push_back(key_time[i]);
          for (const std::size_t t : targets) weights.push_back(t == i ? 1.0f : 0.0f);
        }
        if (last_run && hold) {
          times.push_back(hold_end);
          for (const std::size_t t : targets) weights.push_back(t == n - 1 ? 1.0f : 0.0f);
        }
        // The weights of a morph target channel are scalars, targets.size() per key (glTF 2.0, 3.11).
        add_sampler(times, weights, 1, "LINEAR", r, "weights");
      }
      if (runs.size() > 1) {
        std::vector<float> times, scale;
        const auto key = [&](float t, float v) { times.push_back(t), scale.insert(scale.end(), {v, v, v}); };
        if (r > 0) key(0.0f, 0.0f);
        key(key_time[runs[r].first], 1.0f);
        if (!last_run) key(key_time[runs[r + 1].first], 0.0f);
        if (last_run && hold) key(hold_end, 1.0f);
        add_sampler(times, scale, 3, "STEP", r, "scale");
      }
    }
    json frame_ids = json::array(), times_s = json::array();
    for (const ExportFrame& f : frames) frame_ids.push_back(f.index), times_s.push_back(f.time_s);
    j["animations"] = json::array({{{"name", "trajectory"},
                                    {"samplers", samplers},
                                    {"channels", channels},
                                    {"extras", {{"ctsurg_frames", frame_ids}, {"ctsurg_time_s", times_s}, {"ctsurg_time_scale", options.time_scale}}}}});
  }

  while (b.bin.size() % 4 != 0) b.bin.push_back('\0');
  j["bufferViews"] = b.views;
  j["accessors"] = b.accessors;
  j["buffers"] = json::array({{{"byteLength", b.bin.size()}}});
  s.bytes = static_cast<int64_t>(b.bin.size());

  std::vector<std::pair<std::string, std::string>> files;
  const std::string name = output.filename().string();
  if (format == "gltf") {
    const std::string bin_name = std::filesystem::path(output).replace_extension(".bin").filename().string();
    j["buffers"][0]["uri"] = uri_encode(bin_name);
    files.emplace_back(name, j.dump());
    files.emplace_back(bin_name, std::move(b.bin));
    s.bytes += static_cast<int64_t>(files.front().second.size());
    if (summary) *summary = s;
    return files;
  }
  // GLB (glTF 2.0, section 4): a 12-byte header, the JSON chunk padded with spaces, the BIN chunk.
  std::string text = j.dump();
  while (text.size() % 4 != 0) text.push_back(' ');
  std::string glb = "glTF";
  append_gltf_u32(glb, 2);
  append_gltf_u32(glb, static_cast<uint32_t>(12 + 8 + text.size() + 8 + b.bin.size()));
  append_gltf_u32(glb, static_cast<uint32_t>(text.size()));
  glb += "JSON" + text;
  append_gltf_u32(glb, static_cast<uint32_t>(b.bin.size()));
  glb += std::string("BIN\0", 4);
  glb += b.bin;
  files.emplace_back(name, std::move(glb));
  s.bytes = static_cast<int64_t>(files.front().second.size());
  if (summary) *summary = s;
  return files;
}

std::string add_gltf_animation(OutputUnit& unit, const std::filesystem::path& output, const SurfaceMesh& surface,
                               const Trajectory* trajectory, const GltfAnimationOptions& options,
                               GltfAnimationSummary* summary) {
  const auto paths = gltf_animation_files(output);
  auto files = export_gltf_animation(output, surface, trajectory, options, summary);
  for (std::size_t k = 0; k < files.size(); ++k) {
    AtomicOutput& out = unit.add(paths.at(k));
    write_file_checked(out.temp_path(), files[k].second, paths[k].string());
  }
  return std::move(files.front().second);
}

}  // namespace ctsurg
