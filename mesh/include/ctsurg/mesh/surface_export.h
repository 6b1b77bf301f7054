// Export of a surface mesh to the formats other programs open (Blender, MeshLab, slicers, web
// viewers), through Assimp, chosen by the output's suffix:
//   .glb (binary glTF 2), .gltf (glTF 2 JSON with a .bin beside it), .obj (Wavefront, no .mtl),
//   .stl (binary STL), .ply (PLY)
// Coordinates are written as they are: LPS millimetres (glTF's "metres, +Y up" convention is not
// applied; a viewer shows the patient in mm with superior along +Z). Normals go with the vertices
// where the format has them (not STL, which stores face normals only).
// A mesh with uvs (and tangents) from ctsurg-normalmap exports them as texture coordinates (and,
// for glTF, the TANGENT attribute, added after Assimp, whose 5.2 exporter drops it). With a normal
// map the material (a PBR tissue colour) uses it as its normal texture: embedded (.glb: in the
// binary chunk; .gltf: a data URI), or, when `normal_map_uri` is given, referenced by that relative
// URI (the caller writes the PNG there).
#pragma once

#include "ctsurg/core/surface_mesh_file.h"

#include "ctsurg/core/atomic_output.h"

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace ctsurg {

// Assimp exporter id for `path`'s suffix ("glb2", "gltf2", "objnomtl", "stlb", "ply"), or "" when
// the suffix is none of the export formats.
std::string surface_export_format(const std::filesystem::path& path);

// Writes `mesh` to `path` (a temporary path is fine: the format comes from `format_of`'s suffix,
// defaulting to `path`). InputError(path, "suffix", ...) for an unknown suffix; RuntimeError when
// Assimp fails. Not atomic by itself: callers write to an AtomicOutput's temp_path().
void export_surface_mesh(const std::filesystem::path& path, const SurfaceMesh& mesh,
                         const std::filesystem::path& format_of = {}, const std::string& normal_map_uri = {});

// An export of `mesh` to `output` (by its suffix) and the files that go with it, all written to
// temporary names in the output's folder at construction; commit() moves every one into place, and
// an export never committed leaves nothing behind. .gltf writes NAME.bin beside NAME.gltf and names
// it inside the JSON, so it is exported into a private folder under its final name and moved; with
// a normal map (`normal_map_png`, the encoded PNG) its material references NAME_normal_map.png,
// written beside it. Other formats embed the map (.glb) or have no material.
class PendingSurfaceExport {
 public:
  PendingSurfaceExport(const std::filesystem::path& output, const SurfaceMesh& mesh,
                       const std::vector<uint8_t>& normal_map_png = {});
  void commit();

 private:
  AtomicOutput out_;
  std::unique_ptr<AtomicOutput> bin_, png_;
};

// Writes `bytes` to `path` (a temporary path of an AtomicOutput); RuntimeError naming `name` on failure.
void write_file_bytes(const std::filesystem::path& path, const std::vector<uint8_t>& bytes, const std::string& name);

}  // namespace ctsurg
