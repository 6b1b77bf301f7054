// Per-particle (grid) and per-spring (explicit) cutting kernels: segment-triangle intersection
// (Moller & Trumbore 1997, in double: cutting is rare and must not miss a spring to rounding).
#pragma once

#include "kernel_support.h"

#include "ctsurg/sim/spring_grid_model.h"

#include <cstdint>

namespace ctsurg::sim {

struct TriangleView {
  double a[3], b[3], c[3];  // LPS mm
};

// Whether the segment p -> q (LPS mm) meets the triangle (boundary included).
CTSURG_HD inline bool segment_crosses_triangle(const double p[3], const double q[3], const TriangleView& t) {
  const double e1[3] = {t.b[0] - t.a[0], t.b[1] - t.a[1], t.b[2] - t.a[2]};
  const double e2[3] = {t.c[0] - t.a[0], t.c[1] - t.a[1], t.c[2] - t.a[2]};
  const double d[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
  const double h[3] = {d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2], d[0] * e2[1] - d[1] * e2[0]};
  const double det = e1[0] * h[0] + e1[1] * h[1] + e1[2] * h[2];
  // Parallel (or a degenerate triangle or segment): no crossing.
  const double scale = (e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]) * (e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2]) *
                       (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  if (det * det <= 1e-24 * scale || scale == 0) return false;
  const double inv = 1.0 / det;
  const double s[3] = {p[0] - t.a[0], p[1] - t.a[1], p[2] - t.a[2]};
  const double u = (s[0] * h[0] + s[1] * h[1] + s[2] * h[2]) * inv;
  if (u < 0 || u > 1) return false;
  const double r[3] = {s[1] * e1[2] - s[2] * e1[1], s[2] * e1[0] - s[0] * e1[2], s[0] * e1[1] - s[1] * e1[0]};
  const double v = (d[0] * r[0] + d[1] * r[1] + d[2] * r[2]) * inv;
  if (v < 0 || u + v > 1) return false;
  const double along = (e2[0] * r[0] + e2[1] * r[1] + e2[2] * r[2]) * inv;
  return along >= 0 && along <= 1;
}

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
