// The surface mesh: a closed, consistently oriented triangle mesh of an isosurface (written by
// ctsurg-surface, read by later mesh and simulation stages), with each vertex tied to the lattice it
// was extracted from so that a simulation moving the lattice's nodes can move the surface with it.
//
//   /provenance
//   /surface/vertices      (#V, 3) float32  LPS mm
//   /surface/normals       (#V, 3) float32  unit, outward (towards decreasing field value)
//   /surface/triangles     (#F, 3) uint32   vertex indices, counter-clockwise seen from outside
//   /surface/grid_cell     (#V, 3) int32    (i, j, k) of the lattice cell holding the vertex
//   /surface/grid_weights  (#V, 8) float32  trilinear weights of that cell's corners, corner c at
//                                            (i + (c & 1), j + (c >> 1 & 1), k + (c >> 2 & 1))
//   /surface/nearest_node  (#V, 3) int32    (i, j, k) of the nearest lattice node inside the surface
//   /surface attributes: iso, quantity (the field's), source_dataset, vertices, triangles, frame "LPS",
//                        units "mm", and the lattice: dims, spacing_mm, origin_mm, direction (as volumes)
//
// Optional, written by ctsurg-normalmap (each present only when the mesh has it):
//   /surface/uvs           (#V, 2) float32  texture coordinates in [0, 1], glTF convention: u to the
//                                            right, v down the image (v = 0 is the image's top row)
//   /surface/tangents      (#V, 4) float32  unit tangent along +u (xyz, LPS, orthogonal to the normal)
//                                            and handedness w = +-1: bitangent = w * normal x tangent
//                                            points along -v (up the image), as glTF's TANGENT
//   /surface/source_vertex (#V)    uint32   index of the vertex of the surface this one was copied
//                                            from (atlas seams duplicate vertices); the grid tie is
//                                            copied with it. @source_vertices holds that surface's count
//   /surface/normal_map    (H, W, 3) uint8 or uint16  tangent-space normal map, row 0 = v 0, RGB =
//                                            (n_t, n_b, n_n + 1) / 2 scaled to the full integer range
//                                            (n_t along the tangent, n_b along the bitangent)
//                          attributes on /surface: normal_map_space "tangent", normal_map_bits 8 or 16
//
// plus an XDMF sidecar describing a triangle mesh. See docs/formats.md.
#pragma once

#include "ctsurg/core/atomic_output.h"
#include "ctsurg/core/image_geometry.h"
#include "ctsurg/core/provenance.h"

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace ctsurg {

// A tangent-space normal map (see the file layout above for the encoding).
struct NormalMapImage {
  int64_t width = 0, height = 0;  // texels
  int bits = 8;                   // 8 or 16: the value range is 0 .. 2^bits - 1
  std::vector<uint16_t> rgb;      // height x width x 3, row-major, row 0 at v = 0 (top of the image)

  bool empty() const { return rgb.empty(); }
};

struct SurfaceMesh {
  std::vector<float> vertices;       // #V x 3, LPS mm, row-major
  std::vector<float> normals;        // #V x 3, unit, outward
  std::vector<uint32_t> triangles;   // #F x 3, counter-clockwise seen from outside
  std::vector<int32_t> grid_cell;    // #V x 3, cell (i, j, k) of `lattice` holding the vertex
  std::vector<float> grid_weights;   // #V x 8, trilinear weights of the cell's corners (sum 1)
  std::vector<int32_t> nearest_node; // #V x 3, nearest inside node of `lattice` (value >= iso)
  ImageGeometry lattice;             // the lattice the surface was extracted from (nodes = voxel centres)
  double iso = 0.0;                  // the isovalue, in the field's units
  std::string quantity;              // the field, e.g. "fraction" or "HU"
  std::string source_dataset;        // where the field came from, e.g. "/grid/fraction"
  // Optional (empty when absent): texture atlas, tangent frames and normal map (ctsurg-normalmap).
  std::vector<float> uvs;            // #V x 2, in [0, 1]; u right, v down the image
  std::vector<float> tangents;       // #V x 4, unit tangent along +u (LPS) and handedness +-1
  std::vector<uint32_t> source_vertex;  // #V, vertex of the unsplit surface this one copies
  int64_t source_vertex_count = 0;   // vertex count of that unsplit surface (> every source_vertex)
  NormalMapImage normal_map;         // empty, or the tangent-space normal map the uvs address

  int64_t vertex_count() const { return static_cast<int64_t>(vertices.size() / 3); }
  int64_t triangle_count() const { return static_cast<int64_t>(triangles.size() / 3); }
};

// Writes `path` (and its .xdmf sidecar) atomically. InputError(path, "/surface", ...) for an empty
// mesh or inconsistent array sizes (optional arrays included: each empty or of its full size).
void write_surface_mesh_file(const std::filesystem::path& path, const SurfaceMesh& mesh, const Provenance& provenance,
                             OutputUnit* unit = nullptr);
// Reads a surface mesh file; InputError naming the file and object when it is not one or when an
// array has the wrong shape or a triangle names a vertex that does not exist.
SurfaceMesh read_surface_mesh_file(const std::filesystem::path& path);

}  // namespace ctsurg
