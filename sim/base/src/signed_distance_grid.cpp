#include "ctsurg/sim/base/signed_distance_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ctsurg::sim {
namespace {

using V3 = std::array<double, 3>;

V3 sub(const double* a, const double* b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot(const V3& a, const V3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

}  // namespace

double point_triangle_distance(const V3& p, const double* a, const double* b, const double* c) {
  // Ericson 5.1.5: the closest point by Voronoi regions of the vertices, edges and face.
  const V3 ab = sub(b, a), ac = sub(c, a), ap = sub(p.data(), a);
  auto at = [&](double v, double w) {
    const V3 q{a[0] + v * ab[0] + w * ac[0], a[1] + v * ab[1] + w * ac[1], a[2] + v * ab[2] + w * ac[2]};
    return std::sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
  };
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return at(0, 0);
  const V3 bp = sub(p.data(), b);
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return at(1, 0);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return at(d1 / (d1 - d3), 0);
  const V3 cp = sub(p.data(), c);
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return at(0, 1);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return at(0, d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return at(1 - w, w);  // on edge bc: a + (1 - w) ab + w ac
  }
  const double denom = va + vb + vc;
  if (!(std::abs(denom) > 0)) return std::min({at(0, 0), at(1, 0), at(0, 1)});  // degenerate: its corners
  return at(vb / denom, vc / denom);
}

SignedDistanceGrid bake_signed_distance_grid(const TriangleMesh& mesh, double h, int margin_cells) {
  const size_t nf = mesh.faces.size() / 3;
  V3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    lo[i % 3] = std::min(lo[i % 3], mesh.vertices[i]);
    hi[i % 3] = std::max(hi[i % 3], mesh.vertices[i]);
  }
  SignedDistanceGrid g;
  g.spacing = h;
  for (size_t a = 0; a < 3; ++a) {
    g.origin[a] = lo[a] - margin_cells * h;
    g.dims[a] = static_cast<int32_t>(std::ceil((hi[a] - lo[a]) / h)) + 2 * margin_cells + 1;
  }
  const int64_t nx = g.dims[0], ny = g.dims[1], nz = g.dims[2];
  const auto id = [&](int64_t i, int64_t j, int64_t k) { return static_cast<size_t>(i + nx * (j + ny * k)); };
  const auto node = [&](int64_t i, int64_t j, int64_t k) -> V3 {
    return {g.origin[0] + static_cast<double>(i) * h, g.origin[1] + static_cast<double>(j) * h, g.origin[2] + static_cast<double>(k) * h};
  };
  const size_t count = static_cast<size_t>(nx * ny * nz);
  std::vector<double> dist(count, std::numeric_limits<double>::infinity());
  std::vector<int32_t> closest(count, -1);
  const double* v = mesh.vertices.data();
  const uint32_t* f = mesh.faces.data();
  const auto tri = [&](size_t t, int corner) { return v + 3 * static_cast<size_t>(f[3 * t + static_cast<size_t>(corner)]); };

  // Exact distances in a band of two cells around each triangle.
  for (size_t t = 0; t < nf; ++t) {
    std::array<int64_t, 3> c0{}, c1{};
    for (size_t a = 0; a < 3; ++a) {
      const double mn = std::min({tri(t, 0)[a], tri(t, 1)[a], tri(t, 2)[a]});
      const double mx = std::max({tri(t, 0)[a], tri(t, 1)[a], tri(t, 2)[a]});
      c0[a] = std::clamp<int64_t>(static_cast<int64_t>(std::floor((mn - g.origin[a]) / h)) - 2, 0, g.dims[a] - 1);
      c1[a] = std::clamp<int64_t>(static_cast<int64_t>(std::ceil((mx - g.origin[a]) / h)) + 2, 0, g.dims[a] - 1);
    }
    for (int64_t k = c0[2]; k <= c1[2]; ++k)
      for (int64_t j = c0[1]; j <= c1[1]; ++j)
        for (int64_t i = c0[0]; i <= c1[0]; ++i) {
          const double d = point_triangle_distance(node(i, j, k), tri(t, 0), tri(t, 1), tri(t, 2));
          const size_t n = id(i, j, k);
          // Ties go to the lower triangle index: the same grid whatever the order of evaluation.
          if (d < dist[n] || (d == dist[n] && static_cast<int32_t>(t) < closest[n])) dist[n] = d, closest[n] = static_cast<int32_t>(t);
        }
  }
  // Fast sweeping: each node tries its sweep-direction neighbours' closest triangles; two rounds of
  // the eight directions.
  for (int round = 0; round < 2; ++round) {
    for (int dir = 0; dir < 8; ++dir) {
      const int di = (dir & 1) ? -1 : 1, dj = (dir & 2) ? -1 : 1, dk = (dir & 4) ? -1 : 1;
      for (int64_t kk = 0; kk < nz; ++kk) {
        const int64_t k = dk > 0 ? kk : nz - 1 - kk;
        for (int64_t jj = 0; jj < ny; ++jj) {
          const int64_t j = dj > 0 ? jj : ny - 1 - jj;
          for (int64_t ii = 0; ii < nx; ++ii) {
            const int64_t i = di > 0 ? ii : nx - 1 - ii;
            const size_t n = id(i, j, k);
            const int64_t nb[3][3] = {{i - di, j, k}, {i, j - dj, k}, {i, j, k - dk}};
            for (const auto& q : nb) {
              if (q[0] < 0 || q[0] >= nx || q[1] < 0 || q[1] >= ny || q[2] < 0 || q[2] >= nz) continue;
              const int32_t t = closest[id(q[0], q[1], q[2])];
              if (t < 0 || t == closest[n]) continue;
              const double d = point_triangle_distance(node(i, j, k), tri(static_cast<size_t>(t), 0), tri(static_cast<size_t>(t), 1),
                                                       tri(static_cast<size_t>(t), 2));
              if (d < dist[n]) dist[n] = d, closest[n] = t;
            }
          }
        }
      }
    }
  }
  // Sign: crossings of rows along each axis, counted into the cell after the crossing, then the
  // parity of the running sum; a node inside on two of three axes is inside.
  std::vector<uint8_t> inside_votes(count, 0);
  constexpr double kRowOffset = 0.0137438953;  // of a cell: irrational-looking, so round meshes miss the rows
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, w = (axis + 2) % 3;  // the row's fixed coordinates
    const int64_t na = g.dims[static_cast<size_t>(axis)], nu = g.dims[static_cast<size_t>(u)], nw = g.dims[static_cast<size_t>(w)];
    std::vector<int32_t> crossings(count, 0);
    const auto cid = [&](int64_t a, int64_t iu, int64_t iw) {
      int64_t c[3];
      c[axis] = a, c[u] = iu, c[w] = iw;
      return id(c[0], c[1], c[2]);
    };
    for (size_t t = 0; t < nf; ++t) {
      const double* p[3] = {tri(t, 0), tri(t, 1), tri(t, 2)};
      const double umin = std::min({p[0][u], p[1][u], p[2][u]}), umax = std::max({p[0][u], p[1][u], p[2][u]});
      const double wmin = std::min({p[0][w], p[1][w], p[2][w]}), wmax = std::max({p[0][w], p[1][w], p[2][w]});
      const int64_t u0 = std::max<int64_t>(0, static_cast<int64_t>(std::ceil((umin - g.origin[static_cast<size_t>(u)]) / h - kRowOffset)));
      const int64_t u1 = std::min<int64_t>(nu - 1, static_cast<int64_t>(std::floor((umax - g.origin[static_cast<size_t>(u)]) / h - kRowOffset)));
      const int64_t w0 = std::max<int64_t>(0, static_cast<int64_t>(std::ceil((wmin - g.origin[static_cast<size_t>(w)]) / h - kRowOffset)));
      const int64_t w1 = std::min<int64_t>(nw - 1, static_cast<int64_t>(std::floor((wmax - g.origin[static_cast<size_t>(w)]) / h - kRowOffset)));
      for (int64_t iw = w0; iw <= w1; ++iw) {
        for (int64_t iu = u0; iu <= u1; ++iu) {
          const double pu = g.origin[static_cast<size_t>(u)] + (static_cast<double>(iu) + kRowOffset) * h;
          const double pw = g.origin[static_cast<size_t>(w)] + (static_cast<double>(iw) + kRowOffset) * h;
          // 2D barycentric coordinates of (pu, pw) in the triangle projected along the axis.
          const double e0 = (p[1][u] - pu) * (p[2][w] - pw) - (p[2][u] - pu) * (p[1][w] - pw);
          const double e1 = (p[2][u] - pu) * (p[0][w] - pw) - (p[0][u] - pu) * (p[2][w] - pw);
          const double e2 = (p[0][u] - pu) * (p[1][w] - pw) - (p[1][u] - pu) * (p[0][w] - pw);
          const bool pos = e0 >= 0 && e1 >= 0 && e2 >= 0, neg = e0 <= 0 && e1 <= 0 && e2 <= 0;
          const double area = e0 + e1 + e2;
          if (!(pos || neg) || area == 0) continue;
          const double x = (e0 * p[0][axis] + e1 * p[1][axis] + e2 * p[2][axis]) / area;
          const int64_t a = static_cast<int64_t>(std::ceil((x - g.origin[static_cast<size_t>(axis)]) / h));
          if (a < na) crossings[cid(std::max<int64_t>(a, 0), iu, iw)] += 1;
        }
      }
    }
    for (int64_t iw = 0; iw < nw; ++iw)
      for (int64_t iu = 0; iu < nu; ++iu) {
        int32_t total = 0;
        for (int64_t a = 0; a < na; ++a) {
          const size_t n = cid(a, iu, iw);
          total += crossings[n];
          if (total % 2 == 1) ++inside_votes[n];
        }
      }
  }
  g.phi.resize(count);
  for (size_t n = 0; n < count; ++n) {
    const double d = std::isfinite(dist[n]) ? dist[n] : h * static_cast<double>(nx + ny + nz);
    g.phi[n] = static_cast<float>(inside_votes[n] >= 2 ? -d : d);
  }
  return g;
}

}  // namespace ctsurg::sim
