// Small graph helpers of the mesh's topology code (fem_cutting.cpp, fem_contact.cpp): a union-find whose
// roots are the lowest members (deterministic groups), a CSR adjacency from (row, value) pairs, and a tet's
// outward faces.
#pragma once

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <utility>
#include <vector>

namespace ctsurg::sim {

// The faces of a positively oriented tet (corners 0, 1, 2, 3), wound outwards: opposite corner 3, 2, 0, 1.
inline constexpr int kTetOutwardFaces[4][3] = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};

struct UnionFind {
  std::vector<int32_t> parent;
  explicit UnionFind(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int32_t find(int32_t x) {
    while (parent[static_cast<size_t>(x)] != x) x = parent[static_cast<size_t>(x)] = parent[static_cast<size_t>(parent[static_cast<size_t>(x)])];
    return x;
  }
  void unite(int32_t a, int32_t b) {
    a = find(a), b = find(b);
    if (a != b) parent[static_cast<size_t>(std::max(a, b))] = std::min(a, b);  // the lower root: deterministic
  }
};

// CSR of `count` rows from (row, value) pairs (sorted here), each row's values in increasing order.
inline void build_csr(int32_t count, std::vector<std::pair<int32_t, int32_t>>& pairs, std::vector<int32_t>& offsets,
                      std::vector<int32_t>& list) {
  std::sort(pairs.begin(), pairs.end());
  offsets.assign(static_cast<size_t>(count) + 1, 0);
  for (const auto& [row, value] : pairs) ++offsets[static_cast<size_t>(row) + 1];
  std::partial_sum(offsets.begin(), offsets.end(), offsets.begin());
  list.resize(pairs.size());
  for (size_t k = 0; k < pairs.size(); ++k) list[k] = pairs[k].second;
}

}  // namespace ctsurg::sim
