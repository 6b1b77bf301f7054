#include "ctsurg/sim/fem/fem_box_mesh.h"

#include "ctsurg/core/error.h"

#include <cmath>
#include <string>
#include <utility>

namespace ctsurg::sim {

FemBoxMesh fem_box_mesh(const std::array<int, 3>& cells, const std::array<double, 3>& size,
                        const std::array<double, 3>& origin) {
  for (int d = 0; d < 3; ++d) {
    if (cells[d] < 1 || cells[d] > 2000) throw InputError("fem box mesh", "cells", "must be in [1, 2000], got " + std::to_string(cells[d]));
    if (!(std::isfinite(size[d]) && size[d] > 0)) throw InputError("fem box mesh", "size", "must be finite and > 0 mm");
  }
  const int nx = cells[0], ny = cells[1], nz = cells[2];
  const int64_t nodes = int64_t(nx + 1) * (ny + 1) * (nz + 1);
  if (nodes > INT32_MAX / 8) throw InputError("fem box mesh", "cells", "too many nodes");
  FemBoxMesh m;
  m.nodes.reserve(3 * nodes);
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) {
        m.nodes.push_back(origin[0] + size[0] * i / nx);
        m.nodes.push_back(origin[1] + size[1] * j / ny);
        m.nodes.push_back(origin[2] + size[2] * k / nz);
      }
  auto id = [&](int i, int j, int k) { return static_cast<int32_t>(i + (nx + 1) * (j + (ny + 1) * k)); };
  // Kuhn: tet per permutation (p0, p1, p2) of the axes: 000 -> +e_p0 -> +e_p1 -> 111. Odd permutations
  // are negatively oriented and get two corners swapped.
  static const int perms[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {2, 1, 0}, {1, 0, 2}};
  m.tets.reserve(static_cast<std::size_t>(24) * nx * ny * nz);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (int p = 0; p < 6; ++p) {
          int c[3] = {0, 0, 0};
          int32_t t[4];
          t[0] = id(i, j, k);
          for (int s = 0; s < 3; ++s) {
            c[perms[p][s]] = 1;
            t[s + 1] = id(i + c[0], j + c[1], k + c[2]);
          }
          if (p >= 3) std::swap(t[2], t[3]);
          m.tets.insert(m.tets.end(), t, t + 4);
        }
  return m;
}

TetMesh tet_mesh_of(const FemBoxMesh& box) {
  TetMesh m;
  m.nodes = box.nodes;
  m.tets = box.tets;
  m.tet_labels.assign(box.tets.size() / 4, 1);
  m.quality.radius_edge_bin_edges = {0, 1};
  m.quality.radius_edge_histogram = {static_cast<int64_t>(m.tet_labels.size())};
  return m;
}

}  // namespace ctsurg::sim
