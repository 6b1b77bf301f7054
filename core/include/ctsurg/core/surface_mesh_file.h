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
// plus an XDMF sidecar describing a triangle mesh. See docs/formats.md.
#pragma once

#include "ctsurg/core/image_geometry.h"
#include "ctsurg/core/provenance.h"

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace ctsurg {

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

  int64_t vertex_count() const { return static_cast<int64_t>(vertices.size() / 3); }
  int64_t triangle_count() const { return static_cast<int64_t>(triangles.size() / 3); }
};

// Writes `path` (and its .xdmf sidecar) atomically. InputError(path, "/surface", ...) for an empty
// mesh or inconsistent array sizes.
void write_surface_mesh_file(const std::filesystem::path& path, const SurfaceMesh& mesh, const Provenance& provenance);
// Reads a surface mesh file; InputError naming the file and object when it is not one or when an
// array has the wrong shape or a triangle names a vertex that does not exist.
SurfaceMesh read_surface_mesh_file(const std::filesystem::path& path);

}  // namespace ctsurg
