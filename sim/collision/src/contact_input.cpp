// The argument checks and the cell size rule shared by the spatial hash's dispatchers (collision_backends.h).
#include "collision_backends.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/base/parallel.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace ctsurg::sim::collision_detail {

namespace {
constexpr int64_t kMaxCount = std::numeric_limits<uint32_t>::max();  // indices are uint32
constexpr double kMaxCellsFromOrigin = 524288;                       // 2^19
}  // namespace

double check_positions(std::span<const double> positions, const char* where, int threads) {
  if (positions.size() % 3 != 0)
    throw InputError(where, "positions", "must be #V x 3 values, got " + std::to_string(positions.size()));
  const int64_t n = static_cast<int64_t>(positions.size());
  if (n / 3 >= kMaxCount)
    throw InputError(where, "positions", "at most 2^32 - 1 vertices, got " + std::to_string(n / 3));
  double largest = 0;
  int64_t bad = -1;
  const int t = cpu::thread_count(threads, n);
#pragma omp parallel for schedule(static) num_threads(t) reduction(max : largest, bad)
  for (int64_t i = 0; i < n; ++i) {
    if (!std::isfinite(positions[i])) bad = std::max(bad, i);
    largest = std::max(largest, std::abs(positions[i]));
  }
  if (bad >= 0)
    throw InputError(where, "positions", "vertex " + std::to_string(bad / 3) + " has a value that is not finite");
  return largest;
}

void check_primitives(std::span<const uint32_t> primitives, int corners, int64_t vertices, const char* where,
                      const char* field, int threads) {
  if (primitives.size() % corners != 0)
    throw InputError(where, field, "must be #P x " + std::to_string(corners) + " indices, got " +
                                       std::to_string(primitives.size()));
  const int64_t n = static_cast<int64_t>(primitives.size());
  if (n / corners >= kMaxCount)
    throw InputError(where, field, "at most 2^32 - 1 primitives, got " + std::to_string(n / corners));
  int64_t bad = -1;
  const int t = cpu::thread_count(threads, n);
#pragma omp parallel for schedule(static) num_threads(t) reduction(max : bad)
  for (int64_t i = 0; i < n; ++i)
    if (primitives[i] >= vertices) bad = std::max(bad, i);
  if (bad >= 0)
    throw InputError(where, field, "primitive " + std::to_string(bad / corners) + " has vertex index " +
                                       std::to_string(primitives[bad]) + ", but there are " +
                                       std::to_string(vertices) + " vertices");
}

void check_objects(std::span<const uint32_t> ids, int64_t count, const char* where, const char* field) {
  if (static_cast<int64_t>(ids.size()) != count)
    throw InputError(where, field, "must have one object id per element (" + std::to_string(count) + "), got " +
                                       std::to_string(ids.size()));
}

double hash_cell_size(std::span<const double> positions, std::span<const uint32_t> primitives, int corners,
                      double requested, double max_abs_coordinate, double margin, const char* where, int threads) {
  if (!std::isfinite(requested) || requested < 0)
    throw InputError(where, "cell_size", "must be finite and >= 0 mm (0: the average edge length), got " +
                                             std::to_string(requested));
  double cell = requested;
  if (cell == 0) {
    cell = average_edge_length_unchecked(positions, primitives, corners, threads);
    if (!(cell > 0)) cell = 1;  // no primitives, or only points: any cell works
    // Tiny primitives far from the origin: the smallest cell the coordinates allow (a chosen cell never fails).
    cell = std::max(cell, 2 * (max_abs_coordinate + margin) / kMaxCellsFromOrigin);
  }
  if ((max_abs_coordinate + margin) / cell > kMaxCellsFromOrigin)
    throw InputError(where, "cell_size",
                     std::to_string(cell) + " mm is too small for coordinates up to " +
                         std::to_string(max_abs_coordinate + margin) +
                         " mm (more than 2^19 cells from the origin); use a larger cell size");
  return cell;
}

void check_entry_count(int64_t entries, const char* where) {
  if (entries > std::numeric_limits<int32_t>::max())
    throw InputError(where, "cell_size",
                     "the primitives' boxes cover " + std::to_string(entries) +
                         " cells (more than 2^31 - 1): the cell size is too small for these primitives");
}

}  // namespace ctsurg::sim::collision_detail
