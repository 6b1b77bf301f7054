// Baking a tangent-space normal map: the detail of a full-resolution surface (detail_field.h)
// transferred to a coarse, texture-mapped surface (uv_atlas.h, tangent_frames.h), as the
// spring-mass surgery simulators do to render a coarse simulated mesh with the look of the
// high-resolution organ (normal mapping of the coarse geometry from a detailed model; Cohen, Olano
// & Manocha 1998, "Appearance-preserving simplification").
//
// Passes:
//  1. Ownership (sequential, triangles in order): each texel whose centre lies in a triangle's UV
//     triangle (edges included, to a relative 1e-7) belongs to the first such triangle. Charts are
//     packed apart, so no texel is claimed by two charts; within a chart ties on shared edges go to
//     the lower triangle index.
//  2. Bake (OpenMP over rows; each texel independent, so the result does not depend on threads):
//     at the texel centre the barycentric coordinates give the surface point P, the interpolated
//     unit normal N and tangent T (Gram-Schmidt against N) with bitangent B = w N x T. Along the
//     line P + t N, |t| <= search_mm, the field is sampled every half full-resolution voxel from
//     t = 0 outwards; the first bracket where (f - iso) changes sign (the detailed surface nearest
//     to P along N) is refined by three regula-falsi steps to t*, and the detail normal is
//     n = -grad f / |grad f| at P + t* N (outward: f decreases out of the tissue). Without a
//     crossing the gradient at P is used, and where that vanishes, N itself (a flat texel).
//     Stored: (n.T, n.B, n.N), encoded c = round((x + 1) / 2 * (2^bits - 1)).
//  3. Dilation (dilate_px passes): every empty texel next to filled ones (8-neighbourhood) takes
//     the normalised mean of their normals, so bilinear filtering and mipmaps at chart borders
//     read the chart's normals instead of the background. Texels still empty get the flat normal
//     (0, 0, 1).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "ctsurg/core/surface_mesh_file.h"
#include "ctsurg/mesh/detail_field.h"

namespace ctsurg {

struct NormalMapBakeOptions {
  int size_px = 2048;      // width = height of the map, texels (16 .. 16384)
  int bits = 8;            // 8 or 16 bits per channel
  int dilate_px = 2;       // passes of dilation into the padding (0 .. 64)
  double search_mm = 0.0;  // how far along the normal to look for the detailed surface; 0: one cell of mesh.lattice
  int threads = 0;         // OpenMP threads; 0 = OpenMP's default
};

struct NormalMapBakeStats {
  int64_t texels_covered = 0;      // texels owned by a triangle
  int64_t texels_on_crossing = 0;  // ... whose normal came from a crossing of the detailed surface
  int64_t texels_dilated = 0;      // texels filled by dilation
  double mean_tilt_deg = 0.0;      // mean angle between baked normals and the mesh normal N, over covered texels
  double search_mm = 0.0;          // the search range used
};

// Texel owners of a UV layout: size_px x size_px, row-major (row = v * size_px), the owning
// triangle of each texel or -1 (pass 1 above). uvs #V x 2, triangles #F x 3.
std::vector<int32_t> texel_owners(const std::vector<float>& uvs, const std::vector<uint32_t>& triangles, int size_px);

// Bakes the normal map of `mesh` (needs uvs and tangents, #V x 2 and #V x 4) from `field`.
// Throws InputError("normal map", field, ...) for missing uvs/tangents or options out of range.
NormalMapImage bake_normal_map(const SurfaceMesh& mesh, const DetailField& field, const NormalMapBakeOptions& options,
                               NormalMapBakeStats* stats = nullptr);

// The unit tangent-space normal (components along T, B, N) stored at texel (x, y) (column, row).
Eigen::Vector3d decode_normal_map_texel(const NormalMapImage& map, int64_t x, int64_t y);

}  // namespace ctsurg
