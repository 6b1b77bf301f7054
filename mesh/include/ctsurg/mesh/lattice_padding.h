// Padding a lattice with a frame of constant nodes, so that marching cubes closes a surface where
// the tissue touches the lattice border (marching cubes has no cells beyond the lattice).
#pragma once

#include "ctsurg/core/volume.h"

#include <cstdint>

namespace ctsurg {

// Returns `field` with `width` extra nodes of value `value` on every side of every axis.
//
// field  scalar volume, x fastest; its geometry (LPS mm, direction matrix included)
// value  the value of the new nodes, e.g. a value below the isovalue ("outside")
// width  nodes added before and after each axis, >= 1
// Returns a volume of dims + 2 * width whose node (i + width, j + width, k + width) is node (i, j, k)
// of `field` at the same LPS position: spacing and direction are kept, the origin moves by
// -width nodes along each index axis. Throws InputError("field", ...) for width < 1 or when the
// padded lattice would not fit in memory (memory_guard.h).
Volume<float> pad_lattice(const Volume<float>& field, float value, int64_t width = 1);

}  // namespace ctsurg
