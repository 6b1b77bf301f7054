#include "ctsurg/core/triangle_mesh_file.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/input_file.h"
#include "ctsurg/core/isolated_call.h"

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

namespace ctsurg {
namespace {

std::string lower_extension(const std::filesystem::path& path) {
  std::string e = path.extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e;
}

template <typename T>
void put(std::string& out, const T* data, size_t count) {
  out.append(reinterpret_cast<const char*>(data), count * sizeof(T));
}

// In the child: assimp's scene flattened to one vertex and one face array (every mesh of the scene,
// untransformed: an instrument file is one part in its own frame), as bytes.
std::string import_with_assimp(const std::string& file) {
  Assimp::Importer importer;
  // Joined vertices make shared edges share indices; no other post-processing changes the geometry.
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const aiScene* scene = importer.ReadFile(file, aiProcess_JoinIdenticalVertices | aiProcess_SortByPType);
  if (scene == nullptr) throw InputError(file, "", std::string("not a readable mesh: ") + importer.GetErrorString());
  std::vector<double> v;
  std::vector<uint32_t> f;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    if (mesh == nullptr || mesh->mVertices == nullptr) continue;
    const size_t base = v.size() / 3;
    if (base + mesh->mNumVertices > 0xffffffffull) throw InputError(file, "vertices", "more than 2^32 vertices");
    for (unsigned i = 0; i < mesh->mNumVertices; ++i) {
      const aiVector3D& p = mesh->mVertices[i];
      v.insert(v.end(), {static_cast<double>(p.x), static_cast<double>(p.y), static_cast<double>(p.z)});
    }
    for (unsigned i = 0; i < mesh->mNumFaces; ++i) {
      const aiFace& face = mesh->mFaces[i];
      if (face.mNumIndices != 3) {
        throw InputError(file, "faces", "face " + std::to_string(f.size() / 3) + " has " + std::to_string(face.mNumIndices) +
                                            " corners; only triangles are accepted (triangulate the mesh)");
      }
      for (unsigned k = 0; k < 3; ++k) {
        if (face.mIndices[k] >= mesh->mNumVertices) throw InputError(file, "faces", "a face index is out of range");
        f.push_back(static_cast<uint32_t>(base + face.mIndices[k]));
      }
      if (static_cast<int64_t>(f.size() / 3) > kMaxTriangleMeshFaces) {
        throw InputError(file, "faces", "more than " + std::to_string(kMaxTriangleMeshFaces) + " triangles");
      }
    }
  }
  const uint64_t nv = v.size() / 3, nf = f.size() / 3;
  std::string out;
  put(out, &nv, 1);
  put(out, &nf, 1);
  put(out, v.data(), v.size());
  put(out, f.data(), f.size());
  return out;
}

// Joins vertices with identical coordinates (assimp keeps an STL's corners apart when they carry
// different face normals), keeping the first occurrence's order: deterministic.
void weld_identical_vertices(TriangleMesh& m) {
  const size_t nv = m.vertices.size() / 3;
  std::vector<uint32_t> order(nv);
  for (size_t i = 0; i < nv; ++i) order[i] = static_cast<uint32_t>(i);
  const auto key = [&](uint32_t i) {
    return std::array<double, 3>{m.vertices[3 * i], m.vertices[3 * i + 1], m.vertices[3 * i + 2]};
  };
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return key(a) < key(b); });
  std::vector<uint32_t> first(nv);  // each vertex's representative: the lowest index with its coordinates
  for (size_t k = 0; k < nv; ++k) {
    first[order[k]] = (k > 0 && key(order[k]) == key(order[k - 1])) ? first[order[k - 1]] : order[k];
  }
  std::vector<uint32_t> renumber(nv, 0xffffffffu);
  std::vector<double> kept;
  kept.reserve(m.vertices.size());
  for (size_t i = 0; i < nv; ++i) {
    if (first[i] != i) continue;
    renumber[i] = static_cast<uint32_t>(kept.size() / 3);
    kept.insert(kept.end(), {m.vertices[3 * i], m.vertices[3 * i + 1], m.vertices[3 * i + 2]});
  }
  for (uint32_t& f : m.faces) f = renumber[first[f]];
  m.vertices = std::move(kept);
}

}  // namespace

TriangleMesh read_triangle_mesh(const std::filesystem::path& path) {
  const std::string file = path.string();
  const std::string ext = lower_extension(path);
  if (ext != ".stl" && ext != ".obj" && ext != ".ply") {
    throw InputError(file, "extension", "expected .stl, .obj or .ply, got '" + ext + "'");
  }
  check_input_file(path);
  const std::uintmax_t bytes = std::filesystem::file_size(path);
  if (bytes > kMaxTriangleMeshFileBytes) {
    throw InputError(file, "", std::to_string(bytes >> 20) + " MiB is over the " +
                                   std::to_string(kMaxTriangleMeshFileBytes >> 20) + " MiB a triangle mesh may have");
  }
  // A time limit for the child: assimp's PLY reader loops forever on a header without end_header
  // (tests/fuzz found it). 5 s and 1 s per 4 MiB: a valid mesh reads far faster.
  const double limit_s = 5.0 + static_cast<double>(bytes) / (4 << 20);
  const std::string bytes_back = isolated_call(file, [&](const ProgressReport&) { return import_with_assimp(file); }, {}, limit_s);
  // The child's answer is ours, but checked as any input: sizes first, then every value.
  uint64_t nv = 0, nf = 0;
  if (bytes_back.size() < 16) throw RuntimeError(file + ": the mesh reader returned a truncated answer");
  std::memcpy(&nv, bytes_back.data(), 8);
  std::memcpy(&nf, bytes_back.data() + 8, 8);
  if (nf > static_cast<uint64_t>(kMaxTriangleMeshFaces) || nv > 3 * nf + 3 ||
      bytes_back.size() != 16 + nv * 3 * sizeof(double) + nf * 3 * sizeof(uint32_t)) {
    throw RuntimeError(file + ": the mesh reader returned an inconsistent answer");
  }
  if (nf == 0 || nv == 0) throw InputError(file, "faces", "the file holds no triangle");
  TriangleMesh mesh;
  mesh.vertices.resize(3 * nv);
  mesh.faces.resize(3 * nf);
  std::memcpy(mesh.vertices.data(), bytes_back.data() + 16, mesh.vertices.size() * sizeof(double));
  std::memcpy(mesh.faces.data(), bytes_back.data() + 16 + mesh.vertices.size() * sizeof(double), mesh.faces.size() * sizeof(uint32_t));
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    if (!std::isfinite(mesh.vertices[i])) {
      throw InputError(file, "vertices", "vertex " + std::to_string(i / 3) + " has a coordinate that is not finite");
    }
  }
  for (const uint32_t index : mesh.faces) {
    if (index >= nv) throw InputError(file, "faces", "a face refers to vertex " + std::to_string(index) + " of " + std::to_string(nv));
  }
  weld_identical_vertices(mesh);
  return mesh;
}

}  // namespace ctsurg
