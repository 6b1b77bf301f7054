// Segment-triangle intersection (Moller & Trumbore 1997), the test behind every cut: a spring
// (springs/kernels/spring_cutting_impl.h) or a surface edge (surface/kernels/surface_cutting_impl.h)
// is cut when its segment meets the blade's triangle. In double: cutting is rare and must not miss a
// spring to rounding.
#pragma once

#include "ctsurg/sim/base/kernels/kernel_support.h"

namespace ctsurg::sim {

// What a kernel sees of a tool_shapes.h Triangle.
struct TriangleView {
  double a[3], b[3], c[3];  // mm
};

// Whether the segment p -> q (mm) meets the triangle (boundary included). A degenerate triangle or
// segment, or one parallel to the triangle, does not.
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

}  // namespace ctsurg::sim
