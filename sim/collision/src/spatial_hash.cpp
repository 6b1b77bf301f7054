// The spatial hash's public functions (spatial_hash.h): Teschner's cell size, the table size, and the CPU
// build with its argument checks.
#include "ctsurg/sim/collision/spatial_hash.h"

#include "collision_backends.h"
#include "ctsurg/core/error.h"
#include "ctsurg/sim/base/parallel.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace ctsurg::sim {

namespace collision_detail {

double average_edge_length_unchecked(std::span<const double> positions, std::span<const uint32_t> primitives,
                                     int corners, int threads) {
  const int64_t count = static_cast<int64_t>(primitives.size()) / corners;
  if (count == 0) return 0;
  // Fixed blocks, each summed in order, then the block sums in order: the same bits for any thread count.
  constexpr int64_t kBlock = 4096;
  const int64_t blocks = (count + kBlock - 1) / kBlock;
  std::vector<double> sums(blocks, 0.0);
  const int t = cpu::thread_count(threads, count);
#pragma omp parallel for schedule(static) num_threads(t)
  for (int64_t b = 0; b < blocks; ++b) {
    double s = 0;
    for (int64_t i = b * kBlock; i < std::min(count, (b + 1) * kBlock); ++i) {
      const uint32_t* c = primitives.data() + i * corners;
      for (int u = 0; u < corners; ++u)
        for (int w = u + 1; w < corners; ++w) {
          const double* x = positions.data() + 3 * static_cast<int64_t>(c[u]);
          const double* y = positions.data() + 3 * static_cast<int64_t>(c[w]);
          s += std::sqrt((x[0] - y[0]) * (x[0] - y[0]) + (x[1] - y[1]) * (x[1] - y[1]) + (x[2] - y[2]) * (x[2] - y[2]));
        }
    }
    sums[b] = s;
  }
  double total = 0;
  for (const double s : sums) total += s;
  const int64_t edges = count * (corners * (corners - 1) / 2);
  return total / static_cast<double>(edges);
}

}  // namespace collision_detail

double average_edge_length(std::span<const double> positions, std::span<const uint32_t> primitives, int corners,
                           int threads) {
  constexpr const char* where = "average edge length";
  if (corners != 3 && corners != 4)
    throw InputError(where, "corners", "must be 3 (triangles) or 4 (tetrahedra), got " + std::to_string(corners));
  collision_detail::check_positions(positions, where, threads);
  collision_detail::check_primitives(primitives, corners, static_cast<int64_t>(positions.size() / 3), where,
                                     "primitives", threads);
  return collision_detail::average_edge_length_unchecked(positions, primitives, corners, threads);
}

uint32_t hash_table_size(int64_t entries) {
  auto is_prime = [](uint64_t n) {
    if (n < 2) return false;
    if (n % 2 == 0) return n == 2;
    for (uint64_t d = 3; d * d <= n; d += 2)
      if (n % d == 0) return false;
    return true;
  };
  uint64_t n = entries < 2 ? 2 : static_cast<uint64_t>(entries);
  while (!is_prime(n)) ++n;
  return static_cast<uint32_t>(n);
}

SpatialHash build_spatial_hash(std::span<const double> positions, std::span<const uint32_t> primitives, int corners,
                               double margin, double cell_size, int threads) {
  constexpr const char* where = "spatial hash";
  if (corners != 3 && corners != 4)
    throw InputError(where, "corners", "must be 3 (triangles) or 4 (tetrahedra), got " + std::to_string(corners));
  if (!std::isfinite(margin) || margin < 0)
    throw InputError(where, "margin", "must be finite and >= 0 mm, got " + std::to_string(margin));
  if (threads < 0) throw InputError(where, "threads", "must be >= 0, got " + std::to_string(threads));
  const double largest = collision_detail::check_positions(positions, where, threads);
  collision_detail::check_primitives(primitives, corners, static_cast<int64_t>(positions.size() / 3), where,
                                     "primitives", threads);
  const double cell =
      collision_detail::hash_cell_size(positions, primitives, corners, cell_size, largest, margin, where, threads);
  const HashedPrimitivesView view{positions.data(), primitives.data(), static_cast<int64_t>(primitives.size()) / corners,
                                  corners, margin, 0};
  return collision_detail::build_hash_cpu(view, cell, where, threads);
}

}  // namespace ctsurg::sim
