// Export of a surface mesh to the formats other programs open (Blender, MeshLab, slicers, web
// viewers), through Assimp, chosen by the output's suffix:
//   .glb (binary glTF 2), .gltf (glTF 2 JSON with a .bin beside it), .obj (Wavefront, no .mtl),
//   .stl (binary STL), .ply (PLY)
// and, written by ctsurg itself (ASCII), the VTK formats 3D Slicer opens as models:
//   .vtk (legacy PolyData, title line "... SPACE=LPS"), .vtp (XML PolyData, FieldData SPACE = "LPS"),
//   both with the normals as point data "Normals"
// glTF (.glb, .gltf) follows its specification: metres, +Y up (superior), +Z front (anterior), +X
// the patient's left, baked into the vertices by the one rotation of gltf_frame.h (det +1, so
// winding, normals and tangent handedness stay right), and no extensions (the material is core
// pbrMetallicRoughness + normalTexture). The other formats have no convention of their own and are
// written as they are: LPS millimetres. Normals go with the vertices where the format has them
// (not STL, which stores face normals only).
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
#include <string>
#include <utility>
#include <vector>

namespace ctsurg {

// Exporter id for `path`'s suffix ("glb2", "gltf2", "objnomtl", "stlb", "ply" for Assimp; "vtk", "vtp"), or "" when
// the suffix is none of the export formats.
std::string surface_export_format(const std::filesystem::path& path);

// The files of an export of `mesh` to `output` (by its suffix), made in memory by Assimp under
// their final names: (file name, bytes), the output's own file first, then what goes beside it (a
// .gltf's .bin). InputError(output, "suffix", ...) for an unknown suffix; RuntimeError when Assimp
// fails (its messages folded in). Nothing is written to disk.
std::vector<std::pair<std::string, std::string>> export_surface_mesh(const std::filesystem::path& output,
                                                                     const SurfaceMesh& mesh,
                                                                     const std::string& normal_map_uri = {});

// Every file an export to `output` writes: the output; for .gltf also NAME.bin and, with a normal
// map, NAME_normal_map.png. For check_output_paths().
std::vector<std::filesystem::path> surface_export_files(const std::filesystem::path& output, bool normal_map);

// Exports `mesh` to `output` and adds its files to `unit`, each written (every error checked) to
// its temporary name; the caller commits the unit. .gltf writes NAME.bin beside NAME.gltf and, with
// a normal map (`normal_map_png`, the encoded PNG), NAME_normal_map.png, which its material
// references. Other formats embed the map (.glb) or have no material.
void add_surface_export(OutputUnit& unit, const std::filesystem::path& output, const SurfaceMesh& mesh,
                        const std::vector<uint8_t>& normal_map_png = {});

}  // namespace ctsurg
