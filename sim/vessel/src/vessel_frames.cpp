#include "ctsurg/sim/vessel/vessel_frames.h"

#include <cmath>

namespace ctsurg::sim {
namespace {

double frame_dot(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

void normalise(double* v) {
  const double n = std::sqrt(frame_dot(v, v));
  if (n > 0) v[0] /= n, v[1] /= n, v[2] /= n;
}

}  // namespace

void polyline_tangents(const double* p, size_t n, double* t) {
  for (size_t i = 0; i < n; ++i) {
    const size_t a = i == 0 ? 0 : i - 1, b = i + 1 == n ? n - 1 : i + 1;
    for (size_t c = 0; c < 3; ++c) t[3 * i + c] = p[3 * b + c] - p[3 * a + c];
    normalise(t + 3 * i);
  }
}

Vec3 plane_spoke(const Vec3& t) {
  const double h = std::hypot(t[0], t[1]);
  if (!(h > 1e-9)) return {1, 0, 0};
  return {-t[1] / h, t[0] / h, 0};
}

void rotation_minimizing_normals(const double* p, const double* t, size_t n, const Vec3& u0, double* u) {
  if (n == 0) return;
  const double d0 = frame_dot(u0.data(), t);
  for (size_t c = 0; c < 3; ++c) u[c] = u0[c] - d0 * t[c];
  normalise(u);
  for (size_t i = 0; i + 1 < n; ++i) {
    const double* r = u + 3 * i;
    const double* ti = t + 3 * i;
    const double* tn = t + 3 * (i + 1);
    double v1[3], rl[3], tl[3], v2[3];
    for (size_t c = 0; c < 3; ++c) v1[c] = p[3 * (i + 1) + c] - p[3 * i + c];
    const double c1 = frame_dot(v1, v1);
    const double a = c1 > 0 ? 2 / c1 * frame_dot(v1, r) : 0, b = c1 > 0 ? 2 / c1 * frame_dot(v1, ti) : 0;
    for (size_t c = 0; c < 3; ++c) rl[c] = r[c] - a * v1[c], tl[c] = ti[c] - b * v1[c];
    for (size_t c = 0; c < 3; ++c) v2[c] = tn[c] - tl[c];
    const double c2 = frame_dot(v2, v2);
    const double e = c2 > 1e-30 ? 2 / c2 * frame_dot(v2, rl) : 0;
    double* out = u + 3 * (i + 1);
    for (size_t c = 0; c < 3; ++c) out[c] = rl[c] - e * v2[c];
    // Keep it exactly perpendicular and unit (the reflections preserve both up to rounding).
    const double d = frame_dot(out, tn);
    for (size_t c = 0; c < 3; ++c) out[c] -= d * tn[c];
    normalise(out);
  }
}

}  // namespace ctsurg::sim
