// Per-triangle and per-vertex surface cutting kernels (see surface_cutting.h).
#pragma once

#include "ctsurg/sim/base/kernels/segment_triangle_impl.h"
#include "ctsurg/sim/base/real.h"

#include <cstdint>

namespace ctsurg::sim {

// Whether triangle f (vertex ids tri[3 f ..]) has an edge crossing the blade.
CTSURG_HD inline bool triangle_crosses_blade(const uint32_t* tri, const float* v, const TriangleView& blade, int64_t f) {
  for (int e = 0; e < 3; ++e) {
    const uint32_t a = tri[3 * f + e], b = tri[3 * f + (e + 1) % 3];
    const uint32_t lo = a < b ? a : b, hi = a < b ? b : a;  // same ordered segment for both triangles of an edge
    const double p[3] = {v[3 * lo], v[3 * lo + 1], v[3 * lo + 2]}, q[3] = {v[3 * hi], v[3 * hi + 1], v[3 * hi + 2]};
    if (segment_crosses_triangle(p, q, blade)) return true;
  }
  return false;
}

// Drops vertex i's slots across the blade and renormalises; returns how many were dropped (0 when
// every slot is across: then nothing changes).
CTSURG_HD inline int detach_vertex(int32_t* particles, Real* weights, const float* v, const Real* x, const Real* y,
                                   const Real* z, const TriangleView& blade, int64_t i) {
  const double p[3] = {v[3 * i], v[3 * i + 1], v[3 * i + 2]};
  bool across[8];
  int dropped = 0, present = 0;
  Real kept = 0;
  for (int c = 0; c < 8; ++c) {
    const int32_t j = particles[8 * i + c];
    across[c] = false;
    if (j < 0) continue;
    ++present;
    const double q[3] = {x[j], y[j], z[j]};
    across[c] = segment_crosses_triangle(p, q, blade);
    if (across[c]) {
      ++dropped;
    } else {
      kept += weights[8 * i + c];
    }
  }
  if (dropped == 0 || dropped == present || !(kept > 0)) return 0;
  for (int c = 0; c < 8; ++c) {
    if (particles[8 * i + c] < 0) continue;
    if (across[c]) {
      particles[8 * i + c] = -1;
      weights[8 * i + c] = 0;
    } else {
      weights[8 * i + c] /= kept;
    }
  }
  return dropped;
}

}  // namespace ctsurg::sim
