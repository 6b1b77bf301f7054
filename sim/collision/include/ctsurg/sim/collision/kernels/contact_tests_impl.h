// Exact per-pair tests of the contact queries (vertex_triangle_contacts.h, vertex_tet_contacts.h) and
// their records, written once for the CPU and CUDA: the closest point on a triangle (Ericson 2005,
// "Real-Time Collision Detection", section 5.1.5), barycentric coordinates in a tetrahedron, and the
// filters (objects, incident primitives). Double precision throughout; degenerate primitives give
// finite results (a degenerate triangle: the closest point on its three edges; a degenerate tet: no
// contact), never NaN.
#pragma once

#include "ctsurg/sim/base/kernels/kernel_support.h"
#include "ctsurg/sim/collision/kernels/spatial_hash_impl.h"

#include <math.h>
#include <stdint.h>

namespace ctsurg::sim {

// A vertex within the query distance of a triangle.
struct VertexTriangleContact {
  uint32_t vertex;         // index into the #V positions
  uint32_t triangle;       // index into the #F triangles
  double closest[3];       // closest point of the triangle, mm
  double barycentric[3];   // closest = b0 a + b1 b + b2 c (each in [0, 1], sum 1), (a, b, c) the triangle's corners
  double distance;         // |vertex - closest|, mm
  double signed_distance;  // distance, negative when the vertex is behind the triangle: (vertex - closest) . n < 0,
                           // n = (b - a) x (c - a) (counter-clockwise seen from outside: negative = inside);
                           // positive for a degenerate triangle (no normal)
};

// A vertex inside a tetrahedron.
struct VertexTetContact {
  uint32_t vertex;         // index into the #V positions
  uint32_t tet;            // index into the #T tets
  double barycentric[4];   // vertex = sum b_i corner_i, each >= -inside_tolerance, sum 1
};

CTSURG_HD inline double dot3(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
CTSURG_HD inline void sub3(const double* a, const double* b, double* out) {
  out[0] = a[0] - b[0], out[1] = a[1] - b[1], out[2] = a[2] - b[2];
}
CTSURG_HD inline void cross3(const double* a, const double* b, double* out) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}

// The closest point to p on segment [a, b], as t with q = a + t (b - a), t in [0, 1]; t = 0 when a = b.
CTSURG_HD inline double closest_on_segment(const double* p, const double* a, const double* b) {
  double ab[3], ap[3];
  sub3(b, a, ab), sub3(p, a, ap);
  const double len2 = dot3(ab, ab);
  if (!(len2 > 0)) return 0;
  const double t = dot3(ap, ab) / len2;
  return t < 0 ? 0 : (t > 1 ? 1 : t);
}

// A triangle whose normal is tiny against the edges at a (|n|^2 = |ab|^2 |ac|^2 sin^2(angle at a), the
// sine squared below 1e-14, or a zero edge): Ericson's region tests divide by |n|^2, so it is treated
// as its three edges.
CTSURG_HD inline bool degenerate_triangle(const double* ab, const double* ac, const double* n) {
  return !(dot3(n, n) > 1e-14 * dot3(ab, ab) * dot3(ac, ac));
}

// The closest point on a degenerate triangle: the closest of its three edges' closest points.
CTSURG_HD inline void closest_on_edges(const double* p, const double* a, const double* b, const double* c, double* bary) {
  const double* from[3] = {a, b, c};
  const double* to[3] = {b, c, a};
  double best = -1;
  for (int e = 0; e < 3; ++e) {
    const double t = closest_on_segment(p, from[e], to[e]);
    double q[3], d[3];
    for (int k = 0; k < 3; ++k) q[k] = from[e][k] + t * (to[e][k] - from[e][k]);
    sub3(p, q, d);
    const double dist2 = dot3(d, d);
    if (best < 0 || dist2 < best) {
      best = dist2;
      bary[0] = bary[1] = bary[2] = 0;
      bary[e] = 1 - t;
      bary[(e + 1) % 3] = t;
    }
  }
}

// Writes (u, v, w) and returns false (not degenerate): the ends of closest_point_triangle's regions.
CTSURG_HD inline bool set3(double* bary, double u, double v, double w) {
  bary[0] = u, bary[1] = v, bary[2] = w;
  return false;
}

// Ericson's ClosestPtPointTriangle (section 5.1.5): the Voronoi region of p among the triangle's
// vertices, edges and face, from six dot products; writes the barycentric coordinates (u, v, w) of the
// closest point q = u a + v b + w c. Returns whether the triangle was degenerate.
CTSURG_HD inline bool closest_point_triangle(const double* p, const double* a, const double* b, const double* c,
                                             double* bary) {
  double ab[3], ac[3], ap[3], n[3];
  sub3(b, a, ab), sub3(c, a, ac), sub3(p, a, ap);
  cross3(ab, ac, n);
  if (degenerate_triangle(ab, ac, n)) {
    closest_on_edges(p, a, b, c, bary);
    return true;
  }
  const double d1 = dot3(ab, ap), d2 = dot3(ac, ap);
  if (d1 <= 0 && d2 <= 0) return set3(bary, 1, 0, 0);  // vertex region a
  double bp[3];
  sub3(p, b, bp);
  const double d3 = dot3(ab, bp), d4 = dot3(ac, bp);
  if (d3 >= 0 && d4 <= d3) return set3(bary, 0, 1, 0);  // vertex region b
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {  // edge region ab (d1 - d3 = |ab|^2 > 0)
    const double v = d1 / (d1 - d3);
    return set3(bary, 1 - v, v, 0);
  }
  double cp[3];
  sub3(p, c, cp);
  const double d5 = dot3(ab, cp), d6 = dot3(ac, cp);
  if (d6 >= 0 && d5 <= d6) return set3(bary, 0, 0, 1);  // vertex region c
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {  // edge region ac (d2 - d6 = |ac|^2 > 0)
    const double w = d2 / (d2 - d6);
    return set3(bary, 1 - w, 0, w);
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {  // edge region bc
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return set3(bary, 0, 1 - w, w);
  }
  const double sum = va + vb + vc;  // |n|^2 in exact arithmetic: > 0 unless degenerate
  if (!(sum > 0)) {  // rounding with p far off the plane: the edges are as close
    closest_on_edges(p, a, b, c, bary);
    return false;
  }
  const double v = vb / sum, w = vc / sum;  // face region
  return set3(bary, 1 - v - w, v, w);
}

// The unsigned contact record of vertex p against triangle (a, b, c); true when within `distance` mm.
CTSURG_HD inline bool vertex_triangle_test(const double* p, const double* a, const double* b, const double* c,
                                           double distance, VertexTriangleContact& r) {
  double* bary = r.barycentric;
  const bool degenerate = closest_point_triangle(p, a, b, c, bary);
  double d[3];
  for (int k = 0; k < 3; ++k) {
    r.closest[k] = bary[0] * a[k] + bary[1] * b[k] + bary[2] * c[k];
    d[k] = p[k] - r.closest[k];
  }
  const double dist2 = dot3(d, d);
  if (!(dist2 <= distance * distance)) return false;
  r.distance = kernel_sqrt(dist2);
  double ab[3], ac[3], n[3];
  sub3(b, a, ab), sub3(c, a, ac);
  cross3(ab, ac, n);
  r.signed_distance = !degenerate && dot3(d, n) < 0 ? -r.distance : r.distance;
  return true;
}

// 6 x the signed volume of tet (a, b, c, d): det(b - a, c - a, d - a).
CTSURG_HD inline double tet_det(const double* a, const double* b, const double* c, const double* d) {
  double u[3], v[3], w[3], n[3];
  sub3(b, a, u), sub3(c, a, v), sub3(d, a, w);
  cross3(v, w, n);
  return dot3(u, n);
}

// Barycentric coordinates of p in tet (x0, x1, x2, x3) as ratios of signed volumes (the corner's
// replaced by p); false for a degenerate tet (|volume| below 1e-12 x its longest edge cubed: a flat
// tet has no inside).
CTSURG_HD inline bool tet_barycentric(const double* p, const double* x0, const double* x1, const double* x2,
                                      const double* x3, double* bary) {
  const double det = tet_det(x0, x1, x2, x3);
  double longest2 = 0;
  const double* x[4] = {x0, x1, x2, x3};
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) {
      double e[3];
      sub3(x[j], x[i], e);
      const double l2 = dot3(e, e);
      longest2 = l2 > longest2 ? l2 : longest2;
    }
  const double scale = longest2 * kernel_sqrt(longest2);
  if (!(fabs(det) > 1e-12 * scale)) return false;
  bary[1] = tet_det(x0, p, x2, x3) / det;
  bary[2] = tet_det(x0, x1, p, x3) / det;
  bary[3] = tet_det(x0, x1, x2, p) / det;
  bary[0] = 1 - bary[1] - bary[2] - bary[3];
  return true;
}

// Which (vertex, primitive) pairs are tested at all: objects, and never a primitive that has the
// vertex as a corner.
struct ContactFilterView {
  const uint32_t* vertex_object;     // #V object ids
  const uint32_t* primitive_object;  // #P object ids
  bool self_contact;                 // also pairs within one object (else only between objects)
};

CTSURG_HD inline bool pair_allowed(const ContactFilterView& f, const uint32_t* corners, int corner_count, uint32_t v,
                                   uint32_t prim) {
  if (!f.self_contact && f.vertex_object[v] == f.primitive_object[prim]) return false;
  for (int c = 0; c < corner_count; ++c)
    if (corners[c] == v) return false;
  return true;
}

// The test of the vertex-triangle query (spatial_hash_impl.h's vertex_candidates): the filter, the
// vertex inside the triangle's box (margin: the distance plus a rounding slack), then the exact test.
struct VertexTriangleTest {
  HashedPrimitivesView triangles;  // corners 3
  ContactFilterView filter;
  double distance;                 // mm

  CTSURG_HD bool operator()(uint32_t v, uint32_t t, VertexTriangleContact& r) const {
    const double* x = triangles.positions;
    const uint32_t* f = triangles.indices + 3 * static_cast<int64_t>(t);
    if (!pair_allowed(filter, f, 3, v, t)) return false;
    const double* p = x + 3 * static_cast<int64_t>(v);
    double lo[3], hi[3];
    primitive_box(triangles, t, lo, hi);
    if (!in_box(p, lo, hi)) return false;
    if (!vertex_triangle_test(p, x + 3 * static_cast<int64_t>(f[0]), x + 3 * static_cast<int64_t>(f[1]),
                              x + 3 * static_cast<int64_t>(f[2]), distance, r))
      return false;
    r.vertex = v, r.triangle = t;
    return true;
  }
};

// The test of the vertex-tet query: the filter, the vertex inside the tet's box (relative margin 8 x the
// tolerance: barycentric coordinates >= -tol put a point at most 4 tol x the box's side outside it), then
// the barycentric coordinates.
struct VertexTetTest {
  HashedPrimitivesView tets;  // corners 4
  ContactFilterView filter;
  double inside_tolerance;    // on the barycentric coordinates

  CTSURG_HD bool operator()(uint32_t v, uint32_t t, VertexTetContact& r) const {
    const double* x = tets.positions;
    const uint32_t* c = tets.indices + 4 * static_cast<int64_t>(t);
    if (!pair_allowed(filter, c, 4, v, t)) return false;
    const double* p = x + 3 * static_cast<int64_t>(v);
    double lo[3], hi[3];
    primitive_box(tets, t, lo, hi);
    if (!in_box(p, lo, hi)) return false;
    if (!tet_barycentric(p, x + 3 * static_cast<int64_t>(c[0]), x + 3 * static_cast<int64_t>(c[1]),
                         x + 3 * static_cast<int64_t>(c[2]), x + 3 * static_cast<int64_t>(c[3]), r.barycentric))
      return false;
    for (int k = 0; k < 4; ++k)
      if (!(r.barycentric[k] >= -inside_tolerance)) return false;
    r.vertex = v, r.tet = t;
    return true;
  }
};

}  // namespace ctsurg::sim
