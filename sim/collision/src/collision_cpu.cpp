// The CPU launchers of the spatial hash's kernels (kernels/spatial_hash_impl.h, contact_tests_impl.h):
// OpenMP over primitives, buckets and vertices. Every pass that produces a variable amount of output
// counts first, prefix-sums, then writes (VTK's FlyingEdges: the output is allocated once and threads
// write disjoint ranges), and the table's buckets are sorted after the fill, so the table and the
// contacts are the same for any thread count. Compiled without FMA contraction (sim/collision/CMakeLists.txt),
// as the CUDA file is (-fmad=false): the same doubles on both.
#include "collision_backends.h"

#include "ctsurg/sim/base/parallel.h"

#include <omp.h>

#include <algorithm>

namespace ctsurg::sim::collision_detail {
namespace {

// Exclusive prefix sum of counts[0, n) in place; returns the total. Two passes over per-thread blocks
// (integer sums: the same for any split).
template <class T>
T exclusive_scan(T* counts, int64_t n, int threads) {
  const int t = cpu::thread_count(threads, n);
  std::vector<T> block_sums(t + 1, 0);
  int team_size = 1;
#pragma omp parallel num_threads(t)
  {
    const int id = omp_get_thread_num(), team = omp_get_num_threads();
    const int64_t begin = n * id / team, end = n * (id + 1) / team;
    T s = 0;
    for (int64_t i = begin; i < end; ++i) s += counts[i];
    block_sums[id + 1] = s;
#pragma omp barrier
#pragma omp single
    {
      team_size = team;
      for (int b = 0; b < team; ++b) block_sums[b + 1] += block_sums[b];
    }
    T running = block_sums[id];
    for (int64_t i = begin; i < end; ++i) {
      const T c = counts[i];
      counts[i] = running;
      running += c;
    }
  }
  return block_sums[team_size];
}

// Count, scan, write for one query.
template <class Test, class Record>
std::vector<Record> query(const HashTableView& table, const Test& test, const double* positions, int64_t vertices,
                          int threads) {
  std::vector<int64_t> offsets(vertices + 1, 0);
  const int t = cpu::thread_count(threads, vertices);
#pragma omp parallel for schedule(dynamic, 1024) num_threads(t)
  for (int64_t v = 0; v < vertices; ++v)
    offsets[v] = vertex_candidates<Test, Record>(table, positions, test, v, nullptr);
  const int64_t total = exclusive_scan(offsets.data(), vertices + 1, threads);
  std::vector<Record> out(total);
#pragma omp parallel for schedule(dynamic, 1024) num_threads(t)
  for (int64_t v = 0; v < vertices; ++v)
    if (offsets[v + 1] > offsets[v]) vertex_candidates<Test, Record>(table, positions, test, v, out.data() + offsets[v]);
  return out;
}

}  // namespace

SpatialHash build_hash_cpu(const HashedPrimitivesView& p, double cell_size, const char* where, int threads) {
  const int t = cpu::thread_count(threads, p.count);
  // 1. entries: each primitive's cell count.
  int64_t entries = 0;
#pragma omp parallel for schedule(static) num_threads(t) reduction(+ : entries)
  for (int64_t i = 0; i < p.count; ++i) entries += cell_count(primitive_cells(p, cell_size, i));
  check_entry_count(entries, where);
  // 2. the table size.
  SpatialHash hash;
  hash.shape = {cell_size, hash_table_size(entries)};
  const int64_t n = hash.shape.table_size;
  // 3. count, scan, fill.
  hash.offsets.assign(n + 1, 0);
  hash.entries.resize(entries);
  std::vector<uint32_t> cursors(n, 0);
  if (t == 1) {  // plain increments (spatial_hash_impl.h's fetch_increment)
    for (int64_t i = 0; i < p.count; ++i) count_primitive<false>(p, hash.shape, hash.offsets.data(), i);
    exclusive_scan(hash.offsets.data(), n + 1, 1);
    for (int64_t i = 0; i < p.count; ++i)
      fill_primitive<false>(p, hash.shape, hash.offsets.data(), cursors.data(), hash.entries.data(), i);
  } else {
#pragma omp parallel for schedule(static) num_threads(t)
    for (int64_t i = 0; i < p.count; ++i) count_primitive<true>(p, hash.shape, hash.offsets.data(), i);
    exclusive_scan(hash.offsets.data(), n + 1, threads);
#pragma omp parallel for schedule(static) num_threads(t)
    for (int64_t i = 0; i < p.count; ++i)
      fill_primitive<true>(p, hash.shape, hash.offsets.data(), cursors.data(), hash.entries.data(), i);
  }
  // 4. each bucket in primitive order.
  const int tb = cpu::thread_count(threads, n);
#pragma omp parallel for schedule(static) num_threads(tb)
  for (int64_t b = 0; b < n; ++b) sort_bucket(hash.offsets.data(), hash.entries.data(), b);
  return hash;
}

std::vector<VertexTriangleContact> vertex_triangle_contacts_cpu(const HashTableView& table, const VertexTriangleTest& test,
                                                                int64_t vertices, int threads) {
  return query<VertexTriangleTest, VertexTriangleContact>(table, test, test.triangles.positions, vertices, threads);
}

std::vector<VertexTetContact> vertex_tet_contacts_cpu(const HashTableView& table, const VertexTetTest& test,
                                                      int64_t vertices, int threads) {
  return query<VertexTetTest, VertexTetContact>(table, test, test.tets.positions, vertices, threads);
}

}  // namespace ctsurg::sim::collision_detail
