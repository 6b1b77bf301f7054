#include "ctsurg/mesh/surface_export.h"

#include "ctsurg/core/checked_write.h"
#include "ctsurg/core/error.h"
#include "ctsurg/core/library_messages.h"
#include "ctsurg/mesh/gltf_frame.h"
#include "ctsurg/mesh/gltf_material.h"
#include "ctsurg/mesh/normal_map_png.h"

#include <assimp/Exporter.hpp>
#include <assimp/IOStream.hpp>
#include <assimp/IOSystem.hpp>
#include <assimp/material.h>
#include <assimp/scene.h>

#include <nlohmann/json.hpp>
#include <spdlog/fmt/fmt.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>

namespace ctsurg {

namespace {

// Assimp's file I/O does not report write errors (a full disk gave a truncated .stl that looked
// finished), so the exporter writes into memory here and ctsurg writes the bytes itself
// (checked_write.h). Files are kept by name; reading is not needed by the exporters.
class MemoryStream final : public Assimp::IOStream {
 public:
  explicit MemoryStream(std::string& bytes) : bytes_(bytes) {}
  size_t Read(void* buffer, size_t size, size_t count) override {
    const size_t n = std::min(count, size ? (bytes_.size() - std::min(at_, bytes_.size())) / size : 0);
    std::memcpy(buffer, bytes_.data() + at_, n * size);
    at_ += n * size;
    return n;
  }
  size_t Write(const void* buffer, size_t size, size_t count) override {
    const size_t n = size * count;
    if (at_ + n > bytes_.size()) bytes_.resize(at_ + n);
    std::memcpy(bytes_.data() + at_, buffer, n);
    at_ += n;
    return count;
  }
  aiReturn Seek(size_t offset, aiOrigin origin) override {
    const size_t base = origin == aiOrigin_SET ? 0 : origin == aiOrigin_CUR ? at_ : bytes_.size();
    at_ = base + offset;
    return aiReturn_SUCCESS;
  }
  size_t Tell() const override { return at_; }
  size_t FileSize() const override { return bytes_.size(); }
  void Flush() override {}

 private:
  std::string& bytes_;
  size_t at_ = 0;
};

class MemoryFiles final : public Assimp::IOSystem {
 public:
  bool Exists(const char* file) const override { return files_.count(file) > 0; }
  char getOsSeparator() const override { return '/'; }
  Assimp::IOStream* Open(const char* file, const char* mode) override {
    std::string& bytes = files_[file];
    if (mode && mode[0] == 'w') bytes.clear();
    if (order_.empty() || std::find(order_.begin(), order_.end(), file) == order_.end()) order_.emplace_back(file);
    return new MemoryStream(bytes);
  }
  void Close(Assimp::IOStream* stream) override { delete stream; }
  // The files in the order they were first opened.
  std::vector<std::pair<std::string, std::string>> take() {
    std::vector<std::pair<std::string, std::string>> out;
    for (const auto& name : order_) out.emplace_back(name, std::move(files_[name]));
    return out;
  }

 private:
  std::map<std::string, std::string> files_;
  std::vector<std::string> order_;
};

void append_u32(std::string& s, uint32_t v) { s.append(reinterpret_cast<const char*>(&v), 4); }

// A mesh's vertex data in the glTF frame (gltf_frame.h): positions in metres, normals and tangent
// xyz rotated, tangent w kept; #V x 3, #V x 3 and #V x 4 (empty without tangents) float32.
struct GltfVertices {
  std::vector<float> positions, normals, tangents;
};

GltfVertices to_gltf_frame(const SurfaceMesh& mesh) {
  const std::size_t nv = static_cast<std::size_t>(mesh.vertex_count());
  GltfVertices g;
  g.positions.resize(3 * nv);
  g.normals.resize(3 * nv);
  for (std::size_t v = 0; v < nv; ++v) {
    const auto p = lps_mm_to_gltf_position(&mesh.vertices[3 * v]);
    const auto n = lps_to_gltf_direction(&mesh.normals[3 * v]);
    std::copy(p.begin(), p.end(), &g.positions[3 * v]);
    std::copy(n.begin(), n.end(), &g.normals[3 * v]);
  }
  if (!mesh.tangents.empty()) {
    g.tangents.resize(4 * nv);
    for (std::size_t v = 0; v < nv; ++v) {
      const auto t = lps_to_gltf_direction(&mesh.tangents[4 * v]);
      std::copy(t.begin(), t.end(), &g.tangents[4 * v]);
      g.tangents[4 * v + 3] = mesh.tangents[4 * v + 3];  // a proper rotation keeps the handedness
    }
  }
  return g;
}

// Removes every "extensions" object and the extensionsUsed / extensionsRequired lists. Assimp 5.2
// declares KHR_materials_volume and FB_ngon_encoding in every file, though nothing of theirs is
// needed: ctsurg's material is core glTF 2.0 (pbrMetallicRoughness + normalTexture), its primitives
// plain triangles. An undeclared or unneeded extension makes strict loaders warn or refuse.
void strip_gltf_extensions(nlohmann::json& j) {
  if (j.is_object()) {
    j.erase("extensions");
    j.erase("extensionsUsed");
    j.erase("extensionsRequired");
    for (auto& [key, value] : j.items()) strip_gltf_extensions(value);
  } else if (j.is_array()) {
    for (auto& value : j) strip_gltf_extensions(value);
  }
}

// Post-processes a glTF export by Assimp (files.front(): the .glb, or the .gltf with its .bin
// beside it): drops the extensions (strip_gltf_extensions), records the frame in asset.extras, and
// adds the tangents. Assimp 5.2's glTF 2 exporter drops tangents, so they are added after it: #V x 4
// float32 tangents are appended to the binary buffer (the GLB's BIN chunk, or the .bin beside a
// .gltf) as a new buffer view and a VEC4 accessor, and the primitive's attributes get TANGENT (glTF
// 2.0, section 3.7.2.1: xyz unit tangent, w = +-1 handedness; the same convention as ctsurg's). The
// exporter joins identical vertices (its enforced aiProcess_JoinIdenticalVertices), so each
// exported vertex is matched to the mesh vertex with the same position and texture coordinates
// (bit for bit: the joined vertex keeps the data of its first copy; v is compared after the same
// two float flips, ours and the exporter's, that produced the written value).
void finish_gltf(std::vector<std::pair<std::string, std::string>>& files, bool binary, const SurfaceMesh& mesh,
                 const GltfVertices& g, const std::string& named) {
  std::string file = files.front().second, bin;
  nlohmann::json j;
  std::string* bin_file = nullptr;
  if (binary) {
    uint32_t json_len = 0, bin_len = 0;
    if (file.size() < 28 || file.compare(0, 4, "glTF") != 0) throw RuntimeError(named + ": unexpected GLB layout");
    std::memcpy(&json_len, file.data() + 12, 4);
    if (28 + static_cast<std::size_t>(json_len) > file.size()) throw RuntimeError(named + ": unexpected GLB layout");
    j = nlohmann::json::parse(file.substr(20, json_len));
    std::memcpy(&bin_len, file.data() + 20 + json_len, 4);
    bin = file.substr(28 + json_len, bin_len);
  } else {
    j = nlohmann::json::parse(file);
    const std::string uri = j.at("buffers").at(0).at("uri").get<std::string>();
    for (auto& [name, bytes] : files) {
      if (std::filesystem::path(name).filename() == uri) bin_file = &bytes;
    }
    if (!bin_file) throw RuntimeError(named + ": the glTF exporter wrote no '" + uri + "'");
    bin = *bin_file;
  }
  strip_gltf_extensions(j);
  j["asset"]["extras"] = {{"ctsurg_frame", kGltfFrameNote}};
  if (!g.tangents.empty() && !mesh.uvs.empty()) {
    auto& primitive = j.at("meshes").at(0).at("primitives").at(0);
    // The floats of a tightly packed float accessor.
    const auto floats = [&](const char* attribute, std::size_t width) {
      const auto& a = j.at("accessors").at(primitive.at("attributes").at(attribute).get<std::size_t>());
      const auto& view = j.at("bufferViews").at(a.at("bufferView").get<std::size_t>());
      const std::size_t count = a.at("count").get<std::size_t>();
      const std::size_t offset = view.value("byteOffset", std::size_t{0}) + a.value("byteOffset", std::size_t{0});
      if (view.value("byteStride", 4 * width) != 4 * width || offset + 4 * width * count > bin.size()) {
        throw RuntimeError(named + ": unexpected glTF accessor layout");
      }
      std::vector<float> out(width * count);
      std::memcpy(out.data(), bin.data() + offset, out.size() * sizeof(float));
      return out;
    };
    const std::vector<float> pos = floats("POSITION", 3), uv = floats("TEXCOORD_0", 2);
    const std::size_t n = pos.size() / 3;
    using Key = std::array<uint32_t, 5>;
    const auto key_of = [](const float* p, float u, float v) {
      Key k;
      std::memcpy(k.data(), p, 12);
      std::memcpy(&k[3], &u, 4);
      std::memcpy(&k[4], &v, 4);
      return k;
    };
    std::map<Key, std::size_t> index;
    for (std::size_t v = 0; v < static_cast<std::size_t>(mesh.vertex_count()); ++v) {
      const float flipped = 1.0f - mesh.uvs[2 * v + 1];  // ours (export_surface_mesh)
      index.emplace(key_of(&g.positions[3 * v], mesh.uvs[2 * v], 1.0f - flipped), v);  // the exporter's
    }
    std::vector<float> tangents(4 * n);
    for (std::size_t v = 0; v < n; ++v) {
      const auto it = index.find(key_of(&pos[3 * v], uv[2 * v], uv[2 * v + 1]));
      if (it == index.end()) throw RuntimeError(named + ": an exported vertex matches no mesh vertex; cannot add tangents");
      std::copy_n(&g.tangents[4 * it->second], 4, &tangents[4 * v]);
    }
    while (bin.size() % 4 != 0) bin.push_back('\0');
    const std::size_t offset = bin.size();
    bin.append(reinterpret_cast<const char*>(tangents.data()), tangents.size() * sizeof(float));
    j["bufferViews"].push_back(
        {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", tangents.size() * sizeof(float)}, {"target", 34962}});
    j["accessors"].push_back({{"bufferView", j["bufferViews"].size() - 1}, {"byteOffset", 0}, {"componentType", 5126},
                              {"count", n}, {"type", "VEC4"}});
    primitive["attributes"]["TANGENT"] = j["accessors"].size() - 1;
    j["buffers"][0]["byteLength"] = bin.size();
  }
  std::string text = j.dump();
  if (!binary) {
    *bin_file = bin;
    files.front().second = text;
    return;
  }
  while (text.size() % 4 != 0) text.push_back(' ');
  while (bin.size() % 4 != 0) bin.push_back('\0');
  std::string glb = "glTF";
  append_u32(glb, 2);
  append_u32(glb, static_cast<uint32_t>(12 + 8 + text.size() + 8 + bin.size()));
  append_u32(glb, static_cast<uint32_t>(text.size()));
  glb += "JSON" + text;
  append_u32(glb, static_cast<uint32_t>(bin.size()));
  glb += std::string("BIN\0", 4) + bin;
  files.front().second = glb;
}

// VTK legacy PolyData, ASCII ("VTK File Formats", VTK User's Guide, sec. 19.3): version 4.2 (classic
// POLYGONS cells, which every VTK reader since 4 reads). The title line carries "SPACE=LPS": 3D
// Slicer (4.11 and later, vtkMRMLModelStorageNode) reads the coordinate frame from it, so the
// model lands on the CT instead of being mirrored through the RAS default of older files.
std::string write_vtk_legacy(const SurfaceMesh& mesh) {
  const int64_t nv = mesh.vertex_count(), nf = mesh.triangle_count();
  fmt::memory_buffer b;
  auto o = std::back_inserter(b);
  fmt::format_to(o, "# vtk DataFile Version 4.2\nctsurg surface, millimetres. SPACE=LPS\nASCII\nDATASET POLYDATA\n"
                    "POINTS {} float\n", nv);
  for (int64_t v = 0; v < nv; ++v) {
    const float* p = &mesh.vertices[static_cast<std::size_t>(3 * v)];
    fmt::format_to(o, "{} {} {}\n", p[0], p[1], p[2]);
  }
  fmt::format_to(o, "POLYGONS {} {}\n", nf, 4 * nf);
  for (int64_t f = 0; f < nf; ++f) {
    const uint32_t* t = &mesh.triangles[static_cast<std::size_t>(3 * f)];
    fmt::format_to(o, "3 {} {} {}\n", t[0], t[1], t[2]);
  }
  fmt::format_to(o, "POINT_DATA {}\nNORMALS Normals float\n", nv);
  for (int64_t v = 0; v < nv; ++v) {
    const float* n = &mesh.normals[static_cast<std::size_t>(3 * v)];
    fmt::format_to(o, "{} {} {}\n", n[0], n[1], n[2]);
  }
  return fmt::to_string(b);
}

// VTK XML PolyData, ASCII. Slicer reads the frame of a .vtp from a FieldData string array named
// "SPACE" (vtkMRMLModelStorageNode::GetCoordinateSystemFromFieldData); ascii string arrays hold
// character codes with a 0 after each string: "LPS" = 76 80 83 0.
std::string write_vtp(const SurfaceMesh& mesh) {
  const int64_t nv = mesh.vertex_count(), nf = mesh.triangle_count();
  fmt::memory_buffer b;
  auto o = std::back_inserter(b);
  fmt::format_to(o, "<?xml version=\"1.0\"?>\n<!-- ctsurg surface, millimetres. SPACE=LPS -->\n"
                    "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
                    "  <PolyData>\n    <FieldData>\n"
                    "      <DataArray type=\"String\" Name=\"SPACE\" NumberOfTuples=\"1\" format=\"ascii\">\n"
                    "        76 80 83 0\n      </DataArray>\n    </FieldData>\n"
                    "    <Piece NumberOfPoints=\"{}\" NumberOfVerts=\"0\" NumberOfLines=\"0\" NumberOfStrips=\"0\" "
                    "NumberOfPolys=\"{}\">\n"
                    "      <PointData Normals=\"Normals\">\n"
                    "        <DataArray type=\"Float32\" Name=\"Normals\" NumberOfComponents=\"3\" format=\"ascii\">\n",
                 nv, nf);
  for (int64_t v = 0; v < nv; ++v) {
    const float* n = &mesh.normals[static_cast<std::size_t>(3 * v)];
    fmt::format_to(o, "{} {} {}\n", n[0], n[1], n[2]);
  }
  fmt::format_to(o, "        </DataArray>\n      </PointData>\n      <Points>\n"
                    "        <DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">\n");
  for (int64_t v = 0; v < nv; ++v) {
    const float* p = &mesh.vertices[static_cast<std::size_t>(3 * v)];
    fmt::format_to(o, "{} {} {}\n", p[0], p[1], p[2]);
  }
  fmt::format_to(o, "        </DataArray>\n      </Points>\n      <Polys>\n"
                    "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
  for (int64_t f = 0; f < nf; ++f) {
    const uint32_t* t = &mesh.triangles[static_cast<std::size_t>(3 * f)];
    fmt::format_to(o, "{} {} {}\n", t[0], t[1], t[2]);
  }
  fmt::format_to(o, "        </DataArray>\n        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
  for (int64_t f = 1; f <= nf; ++f) fmt::format_to(o, "{}\n", 3 * f);
  fmt::format_to(o, "        </DataArray>\n      </Polys>\n    </Piece>\n  </PolyData>\n</VTKFile>\n");
  return fmt::to_string(b);
}

}  // namespace

std::string surface_export_format(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".glb") return "glb2";
  if (ext == ".gltf") return "gltf2";
  if (ext == ".obj") return "objnomtl";
  if (ext == ".stl") return "stlb";
  if (ext == ".ply") return "ply";
  if (ext == ".vtk") return "vtk";
  if (ext == ".vtp") return "vtp";
  return "";
}

std::vector<std::pair<std::string, std::string>> export_surface_mesh(const std::filesystem::path& output,
                                                                     const SurfaceMesh& mesh,
                                                                     const std::string& normal_map_uri) {
  const std::string format = surface_export_format(output);
  if (format.empty()) {
    throw InputError(output.string(), "suffix", "unknown output format; use .h5, .glb, .gltf, .obj, .stl, .ply, .vtk or .vtp");
  }
  if (mesh.vertex_count() == 0 || mesh.triangle_count() == 0) throw InputError(output.string(), "surface", "the mesh is empty");
  // VTK formats are written here (no Assimp exporter exists for them).
  if (format == "vtk") return {{output.filename().string(), write_vtk_legacy(mesh)}};
  if (format == "vtp") return {{output.filename().string(), write_vtp(mesh)}};

  // The scene owns everything it points to and frees it in its destructor.
  aiScene scene;
  scene.mRootNode = new aiNode("surface");
  scene.mRootNode->mNumMeshes = 1;
  scene.mRootNode->mMeshes = new unsigned int[1]{0};
  scene.mNumMaterials = 1;
  scene.mMaterials = new aiMaterial*[1]{new aiMaterial()};
  scene.mNumMeshes = 1;
  scene.mMeshes = new aiMesh*[1]{new aiMesh()};
  aiMesh& m = *scene.mMeshes[0];
  m.mName = "surface";
  m.mMaterialIndex = 0;
  m.mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  const auto nv = static_cast<unsigned>(mesh.vertex_count()), nf = static_cast<unsigned>(mesh.triangle_count());
  m.mNumVertices = nv;
  m.mVertices = new aiVector3D[nv];
  m.mNormals = new aiVector3D[nv];
  // glTF's frame and units are baked into the vertices (gltf_frame.h); OBJ, STL and PLY have no
  // convention of their own and keep LPS millimetres, like the .h5 they come from.
  const bool gltf = format == "glb2" || format == "gltf2";
  const GltfVertices g = gltf ? to_gltf_frame(mesh) : GltfVertices{};
  const std::vector<float>& positions = gltf ? g.positions : mesh.vertices;
  const std::vector<float>& normals = gltf ? g.normals : mesh.normals;
  const std::vector<float>& tangents = gltf ? g.tangents : mesh.tangents;
  for (unsigned v = 0; v < nv; ++v) {
    m.mVertices[v] = aiVector3D(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]);
    m.mNormals[v] = aiVector3D(normals[3 * v], normals[3 * v + 1], normals[3 * v + 2]);
  }
  if (!mesh.uvs.empty()) {
    // Assimp keeps OpenGL's texture origin (v up, from the bottom row); ctsurg's uvs follow glTF
    // (v down, from the top row), and Assimp's glTF exporter flips v back, so both agree.
    m.mNumUVComponents[0] = 2;
    m.mTextureCoords[0] = new aiVector3D[nv];
    for (unsigned v = 0; v < nv; ++v) m.mTextureCoords[0][v] = aiVector3D(mesh.uvs[2 * v], 1.0f - mesh.uvs[2 * v + 1], 0.0f);
  }
  if (!mesh.tangents.empty()) {
    m.mTangents = new aiVector3D[nv];
    m.mBitangents = new aiVector3D[nv];
    for (unsigned v = 0; v < nv; ++v) {
      const aiVector3D t(tangents[4 * v], tangents[4 * v + 1], tangents[4 * v + 2]);
      m.mTangents[v] = t;
      m.mBitangents[v] = (m.mNormals[v] ^ t) * tangents[4 * v + 3];  // w * normal x tangent
    }
  }
  if (!mesh.normal_map.empty() && normal_map_uri.empty()) {
    // The PNG travels inside the file (scene->mTextures, referenced as "*0"): Assimp's glTF 2
    // exporter writes it as an image in the binary chunk (.glb) or a data URI (.gltf).
    const std::vector<uint8_t> png = encode_normal_map_png(mesh.normal_map);
    scene.mNumTextures = 1;
    scene.mTextures = new aiTexture*[1]{new aiTexture()};
    aiTexture& tex = *scene.mTextures[0];
    tex.mWidth = static_cast<unsigned>(png.size());
    tex.mHeight = 0;  // compressed: mWidth is the byte count
    std::strncpy(tex.achFormatHint, "png", sizeof tex.achFormatHint - 1);
    tex.mFilename = aiString("normal_map.png");
    tex.pcData = new aiTexel[(png.size() + sizeof(aiTexel) - 1) / sizeof(aiTexel)];
    std::memcpy(tex.pcData, png.data(), png.size());
  }
  {
    // The tissue material (gltf_material.h), the same with or without a map; with one, its
    // normalTexture points at the map, so any glTF viewer shows the baked detail.
    aiMaterial& mat = *scene.mMaterials[0];
    const aiString name("tissue");
    mat.AddProperty(&name, AI_MATKEY_NAME);
    if (!mesh.normal_map.empty()) {
      const aiString texture_path(normal_map_uri.empty() ? std::string("*0") : normal_map_uri);
      mat.AddProperty(&texture_path, AI_MATKEY_TEXTURE(aiTextureType_NORMALS, 0));
    }
    const std::array<double, 4> c = gltf_linear_colour(kGltfTissueOnScreen);  // glTF's base colour is linear
    const aiColor4D tissue{static_cast<float>(c[0]), static_cast<float>(c[1]), static_cast<float>(c[2]), 1.0f};
    mat.AddProperty(&tissue, 1, AI_MATKEY_COLOR_DIFFUSE);
    const float metallic = float(kGltfTissueMetallic), roughness = float(kGltfTissueRoughness);
    mat.AddProperty(&metallic, 1, AI_MATKEY_METALLIC_FACTOR);
    mat.AddProperty(&roughness, 1, AI_MATKEY_ROUGHNESS_FACTOR);
  }
  m.mNumFaces = nf;
  m.mFaces = new aiFace[nf];
  for (unsigned f = 0; f < nf; ++f) {
    m.mFaces[f].mNumIndices = 3;
    m.mFaces[f].mIndices = new unsigned int[3]{mesh.triangles[3 * f], mesh.triangles[3 * f + 1], mesh.triangles[3 * f + 2]};
  }
  Assimp::Exporter exporter;
  auto* files = new MemoryFiles;  // the exporter owns and deletes it
  exporter.SetIOHandler(files);
  {
    LibraryMessages said;
    if (exporter.Export(&scene, format, output.string()) != aiReturn_SUCCESS) {
      throw RuntimeError(output.string() + ": export failed: " + with_library_text(exporter.GetErrorString(), said.take()));
    }
  }
  std::vector<std::pair<std::string, std::string>> out = files->take();
  if (out.empty() || std::filesystem::path(out.front().first).filename() != output.filename()) {
    throw RuntimeError(output.string() + ": the exporter wrote no file of that name");
  }
  for (auto& [name, bytes] : out) name = std::filesystem::path(name).filename().string();
  if (gltf) finish_gltf(out, format == "glb2", mesh, g, output.string());
  return out;
}

std::vector<std::filesystem::path> surface_export_files(const std::filesystem::path& output, bool normal_map) {
  std::vector<std::filesystem::path> files{output};
  if (surface_export_format(output) == "gltf2") {
    std::filesystem::path bin = output;
    files.push_back(bin.replace_extension(".bin"));
    if (normal_map) files.push_back(output.parent_path() / (output.stem().string() + "_normal_map.png"));
  }
  return files;
}

void add_surface_export(OutputUnit& unit, const std::filesystem::path& output, const SurfaceMesh& mesh,
                        const std::vector<uint8_t>& normal_map_png) {
  const auto paths = surface_export_files(output, !normal_map_png.empty());
  std::string png_uri;
  if (paths.size() == 3) {
    AtomicOutput& png = unit.add(paths[2]);
    write_file_checked(png.temp_path(), std::string_view(reinterpret_cast<const char*>(normal_map_png.data()),
                                                         normal_map_png.size()),
                       paths[2].string());
    png_uri = paths[2].filename().string();
  }
  // A .gltf names its .bin inside the JSON, so the export is made under the final names (in memory)
  // and each file is then written to the temporary name of its output.
  for (const auto& [name, bytes] : export_surface_mesh(output, mesh, png_uri)) {
    const auto path = std::find_if(paths.begin(), paths.end(), [&](const auto& p) { return p.filename() == name; });
    if (path == paths.end()) throw RuntimeError(output.string() + ": the exporter also wrote an unexpected '" + name + "'");
    AtomicOutput& out = unit.add(*path);
    write_file_checked(out.temp_path(), bytes, path->string());
  }
}

}  // namespace ctsurg
