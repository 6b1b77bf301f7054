// Per-index kernels of the spatial hash (spatial_hash.h), written once for the CPU (collision_cpu.cpp,
// OpenMP) and CUDA (spatial_hash_cuda.cu).
//
// Teschner, Heidelberger, Mueller, Pomeranets, Gross 2003, "Optimized Spatial Hashing for Collision
// Detection of Deformable Objects" (VMV 2003): space is cut into cubic cells of edge l; a point (x, y, z)
// lies in cell (floor(x / l), floor(y / l), floor(z / l)), and cell (i, j, k) goes to bucket
//   H(i, j, k) = (i p1 xor j p2 xor k p3) mod n,   p1 = 73856093, p2 = 19349663, p3 = 83492791,
// n the table size (a prime). Every primitive (triangle, tetrahedron) is entered in the bucket of each
// cell its enlarged bounding box touches; a vertex then finds its candidates in the one bucket of its own
// cell. Different cells may share a bucket (hash collisions): the exact test of each candidate sorts that
// out, so the table is a filter that never misses a pair, whatever l and n are.
//
// The table is compressed (CSR): offsets (#buckets + 1) and entries (primitive indices). It is built by
// counting sort: count per bucket (atomic increments), exclusive prefix sum, fill (atomic cursors), then
// each bucket sorted by primitive index (insertion sort: buckets hold a few entries), so that the table,
// and the order in which queries meet candidates, does not depend on the thread schedule.
#pragma once

#include "ctsurg/sim/base/kernels/kernel_support.h"

#include <math.h>
#include <stdint.h>

namespace ctsurg::sim {

// Teschner's three large primes.
constexpr uint32_t kHashPrime1 = 73856093, kHashPrime2 = 19349663, kHashPrime3 = 83492791;

// The primitives that go into the table: `corners` vertex indices per primitive into #V x 3 positions.
struct HashedPrimitivesView {
  const double* positions;  // #V x 3, mm
  const uint32_t* indices;  // #P x corners
  int64_t count;            // #P
  int corners;              // 3 (triangles) or 4 (tetrahedra)
  double margin;            // mm added on every side of each primitive's bounding box
  double relative_margin;   // times the box's largest side, added too (the tets' inside tolerance)
};

// The geometry of the table: cell edge and table size.
struct HashGridShape {
  double cell_size;     // l, mm (> 0)
  uint32_t table_size;  // n, a prime
};

// The compressed table (read-only for queries).
struct HashTableView {
  HashGridShape shape;
  const uint32_t* offsets;  // n + 1: bucket b holds entries[offsets[b], offsets[b + 1])
  const uint32_t* entries;  // primitive indices, increasing within a bucket (a primitive may repeat)
};

CTSURG_HD inline int64_t cell_coordinate(double x, double cell_size) {
  return static_cast<int64_t>(floor(x / cell_size));
}

// H(i, j, k) in 32-bit unsigned arithmetic, as Teschner's 32-bit integers (products wrap modulo 2^32; a
// negative coordinate wraps too, identically on host and device); a 32-bit remainder (the build
// computes one per entry: a 64-bit division would cost about twice as much).
CTSURG_HD inline uint32_t teschner_hash(int64_t i, int64_t j, int64_t k, uint32_t table_size) {
  const uint32_t h = (static_cast<uint32_t>(i) * kHashPrime1) ^ (static_cast<uint32_t>(j) * kHashPrime2) ^
                     (static_cast<uint32_t>(k) * kHashPrime3);
  return h % table_size;
}

CTSURG_HD inline uint32_t point_bucket(const double* p, const HashGridShape& s) {
  return teschner_hash(cell_coordinate(p[0], s.cell_size), cell_coordinate(p[1], s.cell_size),
                       cell_coordinate(p[2], s.cell_size), s.table_size);
}

// The cells [lo, hi] (inclusive) of primitive i's enlarged bounding box.
struct CellBox {
  int64_t lo[3], hi[3];
};

// Primitive i's box: its bounding box enlarged by margin + relative_margin x its largest side, mm. The
// queries' exact tests also require the vertex inside this box (contact_tests_impl.h), with the same
// arithmetic, so that the table never misses a pair the exact test accepts, rounding included (floor(x /
// l) is monotonic in x).
CTSURG_HD inline void primitive_box(const HashedPrimitivesView& p, int64_t i, double* lo, double* hi) {
  const uint32_t* corner = p.indices + i * p.corners;
  for (int a = 0; a < 3; ++a) lo[a] = hi[a] = p.positions[3 * static_cast<int64_t>(corner[0]) + a];
  for (int c = 1; c < p.corners; ++c)
    for (int a = 0; a < 3; ++a) {
      const double x = p.positions[3 * static_cast<int64_t>(corner[c]) + a];
      lo[a] = x < lo[a] ? x : lo[a];
      hi[a] = x > hi[a] ? x : hi[a];
    }
  double side = 0;
  for (int a = 0; a < 3; ++a) side = hi[a] - lo[a] > side ? hi[a] - lo[a] : side;
  const double m = p.margin + p.relative_margin * side;
  for (int a = 0; a < 3; ++a) lo[a] -= m, hi[a] += m;
}

CTSURG_HD inline bool in_box(const double* x, const double* lo, const double* hi) {
  return x[0] >= lo[0] && x[0] <= hi[0] && x[1] >= lo[1] && x[1] <= hi[1] && x[2] >= lo[2] && x[2] <= hi[2];
}

CTSURG_HD inline CellBox primitive_cells(const HashedPrimitivesView& p, double cell_size, int64_t i) {
  double lo[3], hi[3];
  primitive_box(p, i, lo, hi);
  CellBox box;
  for (int a = 0; a < 3; ++a) {
    box.lo[a] = cell_coordinate(lo[a], cell_size);
    box.hi[a] = cell_coordinate(hi[a], cell_size);
  }
  return box;
}

CTSURG_HD inline int64_t cell_count(const CellBox& b) {
  return (b.hi[0] - b.lo[0] + 1) * (b.hi[1] - b.lo[1] + 1) * (b.hi[2] - b.lo[2] + 1);
}

// Increment returning the old value: atomic (relaxed: only the counts matter, the fill is sorted
// after) where several threads share the table, plain where one thread builds it (a locked instruction
// on x86 also orders memory, which stops the scattered accesses of these passes from overlapping).
template <bool kAtomic>
CTSURG_HD inline uint32_t fetch_increment(uint32_t* value) {
#if defined(__CUDA_ARCH__)
  return atomicAdd(value, 1u);
#else
  if constexpr (kAtomic) return __atomic_fetch_add(value, 1u, __ATOMIC_RELAXED);
  else return (*value)++;
#endif
}

// Pass 1 for primitive i: one count in the bucket of each cell of its box.
template <bool kAtomic>
CTSURG_HD inline void count_primitive(const HashedPrimitivesView& p, const HashGridShape& s, uint32_t* bucket_counts,
                                      int64_t i) {
  const CellBox b = primitive_cells(p, s.cell_size, i);
  for (int64_t z = b.lo[2]; z <= b.hi[2]; ++z)
    for (int64_t y = b.lo[1]; y <= b.hi[1]; ++y)
      for (int64_t x = b.lo[0]; x <= b.hi[0]; ++x)
        fetch_increment<kAtomic>(&bucket_counts[teschner_hash(x, y, z, s.table_size)]);
}

// Pass 3 for primitive i (after the prefix sum): its index into each bucket, at the bucket's cursor.
template <bool kAtomic>
CTSURG_HD inline void fill_primitive(const HashedPrimitivesView& p, const HashGridShape& s, const uint32_t* offsets,
                                     uint32_t* cursors, uint32_t* entries, int64_t i) {
  const CellBox b = primitive_cells(p, s.cell_size, i);
  for (int64_t z = b.lo[2]; z <= b.hi[2]; ++z)
    for (int64_t y = b.lo[1]; y <= b.hi[1]; ++y)
      for (int64_t x = b.lo[0]; x <= b.hi[0]; ++x) {
        const uint32_t h = teschner_hash(x, y, z, s.table_size);
        entries[offsets[h] + fetch_increment<kAtomic>(&cursors[h])] = static_cast<uint32_t>(i);
      }
}

// Pass 4 for bucket b: its entries in increasing order (insertion sort; the fill's order is the
// schedule's, the sorted order is not).
CTSURG_HD inline void sort_bucket(const uint32_t* offsets, uint32_t* entries, int64_t b) {
  const uint32_t begin = offsets[b], end = offsets[b + 1];
  for (uint32_t k = begin + 1; k < end; ++k) {
    const uint32_t e = entries[k];
    uint32_t j = k;
    while (j > begin && entries[j - 1] > e) {
      entries[j] = entries[j - 1];
      --j;
    }
    entries[j] = e;
  }
}

// Calls test(v, primitive, record) for each distinct candidate of vertex v's cell, in increasing
// primitive order, and writes the records it accepts to out (when out is not null); returns how many
// it accepted. Test: a struct with `CTSURG_HD bool operator()(uint32_t v, uint32_t prim, Record&) const`.
// The count pass (out null) and the write pass (out at the vertex's offset) visit the same candidates
// in the same order, so the records land sorted by (vertex, primitive).
template <class Test, class Record>
CTSURG_HD inline int64_t vertex_candidates(const HashTableView& t, const double* positions, const Test& test,
                                           int64_t v, Record* out) {
  const uint32_t b = point_bucket(positions + 3 * v, t.shape);
  int64_t found = 0;
  uint32_t previous = 0;
  for (uint32_t k = t.offsets[b]; k < t.offsets[b + 1]; ++k) {
    const uint32_t prim = t.entries[k];
    if (k > t.offsets[b] && prim == previous) continue;  // a primitive entered from two cells of this bucket
    previous = prim;
    Record r{};
    if (!test(static_cast<uint32_t>(v), prim, r)) continue;
    if (out != nullptr) out[found] = r;
    ++found;
  }
  return found;
}

}  // namespace ctsurg::sim
