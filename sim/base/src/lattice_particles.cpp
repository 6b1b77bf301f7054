#include "ctsurg/sim/base/lattice_particles.h"

#include <algorithm>

namespace ctsurg::sim {

int32_t lattice_particle(const ImageGeometry& lattice, const std::vector<int64_t>& cells, int64_t i, int64_t j, int64_t k) {
  const auto& d = lattice.dims;
  if (i < 0 || j < 0 || k < 0 || i >= d[0] || j >= d[1] || k >= d[2]) return -1;
  const int64_t flat = lattice.flat_index(i, j, k);
  const auto it = std::lower_bound(cells.begin(), cells.end(), flat);
  return (it != cells.end() && *it == flat) ? static_cast<int32_t>(it - cells.begin()) : -1;
}

}  // namespace ctsurg::sim
