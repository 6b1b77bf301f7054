// Per-particle (grid) and per-spring (explicit) cutting kernels: a spring is cut when its segment meets
// the blade's triangle (base/kernels/segment_triangle_impl.h).
#pragma once

#include "ctsurg/sim/base/kernels/segment_triangle_impl.h"

#include "ctsurg/sim/springs/spring_grid_model.h"

#include <cstdint>

namespace ctsurg::sim {

// Grid: particle i's spring mask with the springs crossing the triangle cleared. Reads only i's own
// mask, so it can be written back in place.
CTSURG_HD inline uint32_t grid_mask_after_cut(const SpringGridView& g, const Real* x, const Real* y, const Real* z,
                                              const TriangleView& t, int32_t i) {
  uint32_t mask = g.spring_mask[i];
  for (int d = 0; d < kGridDirections; ++d) {
    if (((mask >> d) & 1u) == 0) continue;
    const int32_t j = g.neighbours[static_cast<int64_t>(d) * g.count + i];
    const int32_t lo = i < j ? i : j, hi = i < j ? j : i;
    const double p[3] = {x[lo], y[lo], z[lo]}, q[3] = {x[hi], y[hi], z[hi]};
    if (segment_crosses_triangle(p, q, t)) mask &= ~(1u << d);
  }
  return mask;
}

// Explicit: whether spring s (ends e[2 s], e[2 s + 1]) survives the cut.
CTSURG_HD inline uint8_t explicit_alive_after_cut(const int32_t* ends, const uint8_t* alive, const Real* x, const Real* y,
                                                  const Real* z, const TriangleView& t, int32_t s) {
  if (alive[s] == 0) return 0;
  const int32_t a = ends[2 * s], b = ends[2 * s + 1];
  const double p[3] = {x[a], y[a], z[a]}, q[3] = {x[b], y[b], z[b]};
  return segment_crosses_triangle(p, q, t) ? 0 : 1;
}

}  // namespace ctsurg::sim
