// The bounding box of a model's rest positions (#P x 3 mm, in the run's frame), which scenarios use to
// place tools and fixed regions by fractions of the tissue's extent (at_fraction, box_fraction).
#pragma once

#include <algorithm>
#include <array>
#include <vector>

namespace ctsurg::sim {

struct RestBounds {
  std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  // The point at fractions f of the box (0 = the minimum corner, 1 = the maximum), mm.
  std::array<double, 3> at(const std::array<double, 3>& f) const {
    return {lo[0] + f[0] * (hi[0] - lo[0]), lo[1] + f[1] * (hi[1] - lo[1]), lo[2] + f[2] * (hi[2] - lo[2])};
  }
};

template <typename T>
RestBounds bounds_of(const std::vector<T>& positions) {
  RestBounds b;
  for (size_t i = 0; i < positions.size(); i += 3) {
    for (size_t c = 0; c < 3; ++c) {
      b.lo[c] = std::min<double>(b.lo[c], positions[i + c]);
      b.hi[c] = std::max<double>(b.hi[c], positions[i + c]);
    }
  }
  return b;
}

}  // namespace ctsurg::sim
