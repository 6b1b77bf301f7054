// The spatial hash of Teschner et al. 2003 ("Optimized Spatial Hashing for Collision Detection of
// Deformable Objects", VMV 2003; the FEM paper, section 3.3, detects collisions by spatial hashing):
// primitives (triangles or tetrahedra) entered in a hash table over a uniform grid of cubic cells,
// rebuilt from scratch every step in time linear in the primitives, and queried with vertices, each of
// which reads one bucket (kernels/spatial_hash_impl.h has the hash function and the passes).
//
// Build (counting sort, so that the output is allocated once and the table does not depend on the
// thread schedule, as VTK's FlyingEdges counts, prefix-sums and writes):
//   1. each primitive's box (its bounding box enlarged by a margin) covers c_i cells; E = sum c_i;
//   2. the table size n is the smallest prime >= E (Teschner et al.: a prime, about the number of
//      entries, keeps collisions rare);
//   3. count the entries of each bucket, exclusive prefix sum to offsets, fill at atomic cursors;
//   4. sort each bucket by primitive index.
// Cost O(#P + E + n) time and memory; E is #P times a small constant when the cells are about the
// primitives' size, which Teschner's rule gives: the cell edge is the average edge length of the hashed
// primitives (the paper's parameter study: smaller cells put a primitive in many cells, larger ones
// many primitives in one cell).
//
// Units: positions in mm, in any frame (the local frame of the simulation); all of a call's positions in
// the same frame.
#pragma once

#include "ctsurg/sim/collision/kernels/spatial_hash_impl.h"

#include <cstdint>
#include <span>
#include <vector>

namespace ctsurg::sim {

struct SpatialHash {
  HashGridShape shape{};           // cell edge l (mm) and table size n (prime)
  std::vector<uint32_t> offsets;   // n + 1, bucket b = entries[offsets[b], offsets[b + 1])
  std::vector<uint32_t> entries;   // E primitive indices, increasing within each bucket; a primitive is
                                   // entered once per cell, so twice in a bucket where two of its cells collide

  HashTableView view() const { return {shape, offsets.data(), entries.data()}; }
};

// Teschner's cell size: the average length of the primitives' edges, mm (3 edges per triangle, 6 per
// tet; corners 3 or 4). Deterministic (fixed blocks of primitives summed in order, whatever the thread
// count). 0 when there are no primitives or all are points.
//   positions  #V x 3 row-major, mm
//   primitives #P x corners row-major vertex indices (< #V)
double average_edge_length(std::span<const double> positions, std::span<const uint32_t> primitives, int corners,
                           int threads = 0);

// The smallest prime >= max(entries, 2): the table size for `entries` entries (< 2^31).
uint32_t hash_table_size(int64_t entries);

// Builds the table of the primitives on the CPU (OpenMP, `threads` threads, 0: the default rule of
// sim/base/parallel.h):
//   positions  #V x 3 row-major, mm (finite)
//   primitives #P x corners row-major vertex indices (< #V), corners 3 (triangles) or 4 (tetrahedra)
//   margin     mm (>= 0): each primitive's bounding box is enlarged by it on every side (the query
//              distance of a proximity query)
//   cell_size  mm: the cell edge; 0 picks Teschner's rule (average_edge_length; 1 mm when that is 0; at
//              least 2^-18 of the largest |coordinate| + margin, so that cell coordinates stay small)
// Throws InputError("spatial hash", <field>, ...) for a wrong shape, an index out of range, a value not
// finite, a negative margin or cell size, or a cell size so small that the boxes cover more than 2^31 - 1
// cells or a coordinate is more than 2^19 cells from the origin. A margin much larger than the cell
// puts each primitive in about (1 + 2 margin / cell)^3 cells: pass a larger cell_size then.
SpatialHash build_spatial_hash(std::span<const double> positions, std::span<const uint32_t> primitives, int corners,
                               double margin, double cell_size = 0, int threads = 0);

}  // namespace ctsurg::sim
