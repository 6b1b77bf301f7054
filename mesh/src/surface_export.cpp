#include "ctsurg/mesh/surface_export.h"

#include "ctsurg/core/error.h"

#include <assimp/Exporter.hpp>
#include <assimp/material.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cctype>

namespace ctsurg {

std::string surface_export_format(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".glb") return "glb2";
  if (ext == ".gltf") return "gltf2";
  if (ext == ".obj") return "objnomtl";
  if (ext == ".stl") return "stlb";
  if (ext == ".ply") return "ply";
  return "";
}

void export_surface_mesh(const std::filesystem::path& path, const SurfaceMesh& mesh, const std::filesystem::path& format_of) {
  const std::filesystem::path named = format_of.empty() ? path : format_of;
  const std::string format = surface_export_format(named);
  if (format.empty()) {
    throw InputError(named.string(), "suffix", "unknown output format; use .h5, .glb, .gltf, .obj, .stl or .ply");
  }
  if (mesh.vertex_count() == 0 || mesh.triangle_count() == 0) throw InputError(named.string(), "surface", "the mesh is empty");

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
  for (unsigned v = 0; v < nv; ++v) {
    m.mVertices[v] = aiVector3D(mesh.vertices[3 * v], mesh.vertices[3 * v + 1], mesh.vertices[3 * v + 2]);
    m.mNormals[v] = aiVector3D(mesh.normals[3 * v], mesh.normals[3 * v + 1], mesh.normals[3 * v + 2]);
  }
  m.mNumFaces = nf;
  m.mFaces = new aiFace[nf];
  for (unsigned f = 0; f < nf; ++f) {
    m.mFaces[f].mNumIndices = 3;
    m.mFaces[f].mIndices = new unsigned int[3]{mesh.triangles[3 * f], mesh.triangles[3 * f + 1], mesh.triangles[3 * f + 2]};
  }
  Assimp::Exporter exporter;
  if (exporter.Export(&scene, format, path.string()) != aiReturn_SUCCESS) {
    throw RuntimeError(named.string() + ": export failed: " + exporter.GetErrorString());
  }
}

}  // namespace ctsurg
