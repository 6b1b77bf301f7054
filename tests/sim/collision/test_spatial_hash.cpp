// Tests of sim/collision/spatial_hash.h: the hash function, the table size, Teschner's cell size, and
// the table itself (every primitive in the bucket of every cell its box covers, buckets sorted, the same
// table for any thread count), and the argument checks.
#include "ctsurg/sim/collision/spatial_hash.h"

#include "collision_test_meshes.h"
#include "ctsurg/core/error.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace ctsurg::sim {
namespace {

using collision_test::random_soup;
using collision_test::Scene;

bool is_prime(uint64_t n) {
  if (n < 2) return false;
  for (uint64_t d = 2; d * d <= n; ++d)
    if (n % d == 0) return false;
  return true;
}

TEST(SpatialHash, TableSizeIsTheNextPrime) {
  EXPECT_EQ(hash_table_size(0), 2u);
  EXPECT_EQ(hash_table_size(2), 2u);
  EXPECT_EQ(hash_table_size(10), 11u);
  EXPECT_EQ(hash_table_size(13), 13u);
  EXPECT_EQ(hash_table_size(100), 101u);
  EXPECT_EQ(hash_table_size(1000000), 1000003u);
  for (int64_t e = 0; e < 2000; e += 37) {
    const uint32_t n = hash_table_size(e);
    EXPECT_TRUE(is_prime(n)) << n;
    EXPECT_GE(n, e);
    for (uint64_t m = std::max<int64_t>(e, 2); m < n; ++m) EXPECT_FALSE(is_prime(m)) << m;
  }
}

TEST(SpatialHash, TeschnerHashFunction) {
  // (i p1 xor j p2 xor k p3) mod n with Teschner's primes.
  EXPECT_EQ(teschner_hash(1, 0, 0, 1000003), 73856093u % 1000003u);
  EXPECT_EQ(teschner_hash(0, 1, 0, 1000003), 19349663u % 1000003u);
  EXPECT_EQ(teschner_hash(0, 0, 1, 1000003), 83492791u % 1000003u);
  EXPECT_EQ(teschner_hash(2, 3, 5, 1000003), ((2u * 73856093u) ^ (3u * 19349663u) ^ (5u * 83492791u)) % 1000003u);
  // 32-bit products wrap: 100 * 83492791 > 2^32.
  EXPECT_EQ(teschner_hash(0, 0, 100, 1000003), static_cast<uint32_t>(100ull * 83492791ull % (1ull << 32)) % 1000003u);
  // Negative cells wrap as unsigned: defined, and different from their mirror images.
  EXPECT_LT(teschner_hash(-1, -2, -3, 101), 101u);
  EXPECT_NE(teschner_hash(-1, 0, 0, 1000003), teschner_hash(1, 0, 0, 1000003));
  // Cell coordinates: floor, also below zero.
  EXPECT_EQ(cell_coordinate(2.5, 1.0), 2);
  EXPECT_EQ(cell_coordinate(-0.5, 1.0), -1);
  EXPECT_EQ(cell_coordinate(650.0, 0.5), 1300);
}

TEST(SpatialHash, AverageEdgeLengthIsTeschnersCellSize) {
  const std::vector<double> x = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  const std::vector<uint32_t> tri = {0, 1, 2};
  EXPECT_DOUBLE_EQ(average_edge_length(x, tri, 3), (1 + 1 + std::sqrt(2.0)) / 3);
  const std::vector<uint32_t> tet = {0, 1, 2, 3};
  EXPECT_DOUBLE_EQ(average_edge_length(x, tet, 4), (3 + 3 * std::sqrt(2.0)) / 6);
  EXPECT_EQ(average_edge_length(x, std::vector<uint32_t>{}, 3), 0.0);
  // The default cell is that average; the same bits for any thread count.
  const Scene s = random_soup(20000, 0, 100, 2, {0, 0, 650}, 7);
  const double one = average_edge_length(s.positions, s.primitives, 3, 1);
  EXPECT_EQ(average_edge_length(s.positions, s.primitives, 3, 2), one);
  EXPECT_EQ(average_edge_length(s.positions, s.primitives, 3, 5), one);
  EXPECT_EQ(build_spatial_hash(s.positions, s.primitives, 3, 0.5, 0, 2).shape.cell_size, one);
  EXPECT_EQ(build_spatial_hash(s.positions, s.primitives, 3, 0.5, 3.25, 2).shape.cell_size, 3.25);
}

// Every primitive is in the bucket of every cell of its box; buckets increase; the sizes add up.
void check_table(const Scene& s, int corners, double margin, double cell) {
  const SpatialHash h = build_spatial_hash(s.positions, s.primitives, corners, margin, cell, 2);
  const int64_t count = static_cast<int64_t>(s.primitives.size()) / corners;
  const HashedPrimitivesView view{s.positions.data(), s.primitives.data(), count, corners, margin, 0};
  const uint32_t n = h.shape.table_size;
  ASSERT_EQ(h.offsets.size(), n + 1u);
  EXPECT_TRUE(is_prime(n));
  int64_t entries = 0;
  for (int64_t i = 0; i < count; ++i) entries += cell_count(primitive_cells(view, h.shape.cell_size, i));
  EXPECT_EQ(static_cast<int64_t>(h.entries.size()), entries);
  EXPECT_GE(n, entries);
  EXPECT_EQ(h.offsets[0], 0u);
  EXPECT_EQ(h.offsets[n], h.entries.size());
  for (uint32_t b = 0; b < n; ++b) {
    ASSERT_LE(h.offsets[b], h.offsets[b + 1]);
    EXPECT_TRUE(std::is_sorted(h.entries.begin() + h.offsets[b], h.entries.begin() + h.offsets[b + 1]));
  }
  for (int64_t i = 0; i < count; ++i) {
    const CellBox box = primitive_cells(view, h.shape.cell_size, i);
    for (int64_t z = box.lo[2]; z <= box.hi[2]; ++z)
      for (int64_t y = box.lo[1]; y <= box.hi[1]; ++y)
        for (int64_t x = box.lo[0]; x <= box.hi[0]; ++x) {
          const uint32_t b = teschner_hash(x, y, z, n);
          ASSERT_TRUE(std::binary_search(h.entries.begin() + h.offsets[b], h.entries.begin() + h.offsets[b + 1],
                                         static_cast<uint32_t>(i)))
              << "primitive " << i << " missing from cell (" << x << ", " << y << ", " << z << ")";
        }
  }
}

TEST(SpatialHash, EveryPrimitiveInEveryCellOfItsBox) {
  for (const double cell : {0.0, 0.3, 1.0, 7.0}) {
    SCOPED_TRACE(cell);
    check_table(random_soup(300, 0, 20, 1.5, {-10, 5, 650}, 11), 3, 0.2, cell);
    check_table(collision_test::tet_box({3, 2, 2}, {6, 4, 4}, {0, 0, 650}), 4, 0.0, cell);
  }
  check_table(random_soup(0, 10, 20, 1.5, {0, 0, 0}, 3), 3, 0.2, 0);  // no primitives: an empty table
}

TEST(SpatialHash, SameTableForAnyThreadCount) {
  const Scene s = random_soup(30000, 0, 60, 1.0, {0, 0, 650}, 5);
  const SpatialHash one = build_spatial_hash(s.positions, s.primitives, 3, 0.25, 0, 1);
  for (const int threads : {2, 3, 8}) {
    const SpatialHash other = build_spatial_hash(s.positions, s.primitives, 3, 0.25, 0, threads);
    EXPECT_EQ(other.shape.table_size, one.shape.table_size);
    EXPECT_EQ(other.offsets, one.offsets) << threads;
    EXPECT_EQ(other.entries, one.entries) << threads;
  }
}

TEST(SpatialHash, RejectsBadArguments) {
  const std::vector<double> x = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const std::vector<uint32_t> tri = {0, 1, 2};
  EXPECT_THROW(build_spatial_hash(x, tri, 5, 0), InputError);                                        // corners
  EXPECT_THROW(build_spatial_hash(std::vector<double>{0, 0}, tri, 3, 0), InputError);                // shape
  EXPECT_THROW(build_spatial_hash(x, std::vector<uint32_t>{0, 1}, 3, 0), InputError);                // shape
  EXPECT_THROW(build_spatial_hash(x, std::vector<uint32_t>{0, 1, 3}, 3, 0), InputError);             // index
  EXPECT_THROW(build_spatial_hash(x, tri, 3, -1), InputError);                                       // margin
  EXPECT_THROW(build_spatial_hash(x, tri, 3, 0, -1), InputError);                                    // cell
  EXPECT_THROW(build_spatial_hash(x, tri, 3, 0, std::nan("")), InputError);                          // cell
  EXPECT_THROW(build_spatial_hash(x, tri, 3, 0, 1e-9), InputError);                                  // too fine
  std::vector<double> bad = x;
  bad[4] = std::nan("");
  EXPECT_THROW(build_spatial_hash(bad, tri, 3, 0), InputError);
  try {
    build_spatial_hash(x, std::vector<uint32_t>{0, 1, 3}, 3, 0);
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "primitives");
    EXPECT_NE(std::string(e.what()).find("vertex index 3"), std::string::npos) << e.what();
  }
  // Boxes that cover more than 2^31 cells: refused, not allocated.
  const std::vector<double> big = {0, 0, 0, 400, 0, 0, 0, 400, 400};
  EXPECT_THROW(build_spatial_hash(big, tri, 3, 0, 0.001), InputError);
}

}  // namespace
}  // namespace ctsurg::sim
