// UV atlas: cuts a closed triangle mesh into charts that each map to the plane without overlap and
// packs them into one square texture, for baking and showing a normal map (normal_map_baking.h).
//
// 1. Charts. Triangles are taken as seeds in order of how well their normal aligns with one of the
//    six axes +-x, +-y, +-z (best first, index breaks ties). A chart grows from its seed by breadth-
//    first search over shared edges, taking a neighbour when its unit normal n satisfies
//    n . a >= cos(max_angle) for the chart's axis a (the seed's best axis), and when its projection
//    onto the plane normal to a does not overlap the chart's triangles already placed (a 2D
//    separating-axis test on triangles shrunk by a relative 1e-4 towards their centroids, so
//    neighbours that only share an edge or a corner never count as overlapping). The projection is
//    orthographic along a; since n . a > 0 every projected triangle keeps its orientation, so a
//    chart is locally one-to-one, and the overlap test makes it globally one-to-one (no fold-over
//    where a chart wraps around). Area distortion: UV area / 3D area = n . a in [cos(max_angle), 1].
//    Charts of fewer than 8 triangles (sharp features of a coarse surface, where no axis suits the
//    neighbourhood) are then merged, in chart order, into the adjacent chart whose axis suits them
//    best, when each of their triangles is within 80 deg of that axis and nothing overlaps; those
//    few triangles get an area ratio down to cos(80 deg) = 0.17 instead of a seam and padding each.
// 2. Layout. Each chart is rotated to its principal axes (2D PCA of its vertices; kept unrotated
//    when that gives a smaller box), turned landscape, and scaled by one common density s (texels
//    per mm) so the texel size is the same everywhere on the surface.
// 3. Packing, with `padding_px` empty texels between charts and at the atlas border. First shelf
//    packing of the charts' boxes (sorted by texel height, then width; left to right in rows), the
//    largest s that fits found by bisection. Then shape packing from that s upwards (bisection
//    again): on a raster of b x b texel blocks (b = size_px / 512, at least 1) each chart covers
//    the blocks of its triangles' bounding boxes and is placed, largest first, at the first
//    position (rows from the top, then columns) where its cover grown by ceil(padding / b) blocks
//    meets no covered block, so small charts fill the holes of ring-shaped large ones. The denser
//    of the two layouts is kept (on the heart: 62 % of the atlas covered instead of 40 %).
//    Everything is sequential and ordered, so the atlas is deterministic.
// Seams: a vertex used by several charts is duplicated, one copy per chart, and `source_vertex`
// records the original so per-vertex data (normals, the grid tie) can be copied to the copies.
#pragma once

#include <cstdint>
#include <vector>

#include "ctsurg/core/surface_mesh_file.h"

namespace ctsurg {

struct UvAtlasOptions {
  int size_px = 2048;           // the atlas is size_px x size_px texels (16 .. 16384)
  int padding_px = 4;           // empty texels between charts and at the border (1 .. size_px / 8)
  double max_angle_deg = 60.0;  // a triangle joins a chart when its normal is within this of the axis (1 .. 85)
};

struct UvAtlas {
  std::vector<float> uvs;               // #V' x 2 in [0, 1]: u = x / size_px, v = y / size_px, texel
                                        // (x, y) = (column, row from the top), texel centres at +0.5
  std::vector<uint32_t> triangles;      // #F x 3, the input triangles in input order, indexing the new vertices
  std::vector<uint32_t> source_vertex;  // #V', input vertex each new vertex copies
  std::vector<int32_t> triangle_chart;  // #F, chart of each triangle (0 .. chart_count - 1)
  int64_t chart_count = 0;
  int size_px = 0;             // as in the options
  double texels_per_mm = 0.0;  // the common density s
  double fill_ratio = 0.0;     // total UV area of the triangles / atlas area, in (0, 1)
};

// Builds the atlas of the triangle mesh (vertices #V x 3, LPS mm; triangles #F x 3, consistently
// oriented). Throws InputError("uv atlas", field, ...) for options out of range or an empty mesh,
// RuntimeError when the charts cannot be packed (more charts than the atlas has room for padding).
UvAtlas build_uv_atlas(const std::vector<float>& vertices, const std::vector<uint32_t>& triangles,
                       const UvAtlasOptions& options = {});

// `mesh` with the atlas applied: every per-vertex array (vertices, normals, grid_cell, grid_weights,
// nearest_node) copied through atlas.source_vertex, triangles replaced, uvs and source_vertex set
// (source_vertex_count = mesh's vertex count); tangents and normal map left empty.
SurfaceMesh apply_uv_atlas(const SurfaceMesh& mesh, const UvAtlas& atlas);

}  // namespace ctsurg
