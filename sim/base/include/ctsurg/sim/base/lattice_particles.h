// The particles of a lattice model: one per occupied cell of a cell lattice, numbered by increasing
// flat cell index (i + nx (j + ny k), x fastest). The spring grid model (springs/spring_grid_model.h)
// is built on them; the surface coupling (surface/surface_coupling.h) finds the particle of a cell
// here, so that it needs the lattice and the cell list only, not the model.
#pragma once

#include "ctsurg/core/image_geometry.h"

#include <cstdint>
#include <vector>

namespace ctsurg::sim {

// The particle of cell (i, j, k): the position of its flat index in `cells` (#P flat cell indices,
// increasing), or -1 when the cell holds no particle or lies outside the lattice. O(log #P).
int32_t lattice_particle(const ImageGeometry& lattice, const std::vector<int64_t>& cells, int64_t i, int64_t j, int64_t k);

}  // namespace ctsurg::sim
