#include "ctsurg/mesh/surface_smoothing.h"

#include "ctsurg/core/error.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

namespace ctsurg {

namespace {

// One-ring adjacency of the mesh edges as CSR (sorted, unique neighbours per vertex).
struct Adjacency {
  std::vector<int64_t> first;      // #V + 1
  std::vector<uint32_t> neighbour;  // first[#V]
};

Adjacency one_rings(const SurfaceMesh& mesh) {
  const auto nv = static_cast<std::size_t>(mesh.vertex_count());
  std::vector<uint64_t> pairs;
  pairs.reserve(mesh.triangles.size() * 2);
  for (std::size_t t = 0; t < mesh.triangles.size(); t += 3)
    for (std::size_t c = 0; c < 3; ++c) {
      const uint64_t a = mesh.triangles[t + c], b = mesh.triangles[t + (c + 1) % 3];
      pairs.push_back(a << 32 | b);
      pairs.push_back(b << 32 | a);
    }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  Adjacency adj;
  adj.first.assign(nv + 1, 0);
  adj.neighbour.resize(pairs.size());
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    ++adj.first[(pairs[p] >> 32) + 1];
    adj.neighbour[p] = static_cast<uint32_t>(pairs[p] & 0xffffffffu);
  }
  for (std::size_t v = 0; v < nv; ++v) adj.first[v + 1] += adj.first[v];
  return adj;
}

// x_v += factor * (mean of the one-ring - x_v), read from `in`, written to `out` (Jacobi, so the
// result does not depend on vertex order or thread count).
void laplacian_step(const Adjacency& adj, double factor, const std::vector<double>& in, std::vector<double>& out) {
  const auto nv = static_cast<int64_t>(adj.first.size()) - 1;
#pragma omp parallel for schedule(static)
  for (int64_t v = 0; v < nv; ++v) {
    const auto sv = static_cast<std::size_t>(v);
    const int64_t b = adj.first[sv], e = adj.first[sv + 1];
    for (std::size_t a = 0; a < 3; ++a) {
      if (e == b) {
        out[3 * sv + a] = in[3 * sv + a];
        continue;
      }
      double sum = 0.0;
      for (int64_t n = b; n < e; ++n) sum += in[3 * std::size_t{adj.neighbour[static_cast<std::size_t>(n)]} + a];
      out[3 * sv + a] = in[3 * sv + a] + factor * (sum / double(e - b) - in[3 * sv + a]);
    }
  }
}

// Vertices on an edge that is not shared by exactly two triangles (a border of an open surface):
// the windowed-sinc filter keeps them where they are, as VTK does with boundary smoothing off.
std::vector<char> border_vertices(const SurfaceMesh& mesh) {
  std::vector<uint64_t> edges;
  edges.reserve(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); t += 3)
    for (std::size_t c = 0; c < 3; ++c) {
      const uint64_t a = mesh.triangles[t + c], b = mesh.triangles[t + (c + 1) % 3];
      edges.push_back(std::min(a, b) << 32 | std::max(a, b));
    }
  std::sort(edges.begin(), edges.end());
  std::vector<char> border(static_cast<std::size_t>(mesh.vertex_count()), 0);
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    if (j - i != 2) border[edges[i] >> 32] = border[edges[i] & 0xffffffffu] = 1;
    i = j;
  }
  return border;
}

// out = M in = (in + mean of the one-ring) / 2, M = I - K/2 (Jacobi; a vertex without neighbours is
// its own mean).
void half_laplacian_step(const Adjacency& adj, const std::vector<double>& in, std::vector<double>& out) {
  laplacian_step(adj, 0.5, in, out);
}

// The Hamming-windowed Chebyshev coefficients c_0..c_N of the ideal low-pass filter with pass-band
// angle theta (before normalisation).
std::vector<double> hamming_sinc(int n, double theta) {
  std::vector<double> c(static_cast<std::size_t>(n) + 1);
  for (int i = 0; i <= n; ++i) {
    const double w = 0.54 + 0.46 * std::cos(std::numbers::pi * i / (n + 1));
    c[static_cast<std::size_t>(i)] = i == 0 ? w * theta / std::numbers::pi : 2.0 * w * std::sin(i * theta) / (i * std::numbers::pi);
  }
  return c;
}

double chebyshev_sum(const std::vector<double>& c, double x) {
  // Clenshaw's recurrence for sum_i c_i T_i(x).
  double b1 = 0.0, b2 = 0.0;
  for (std::size_t i = c.size(); i-- > 1;) {
    const double b0 = 2.0 * x * b1 - b2 + c[i];
    b2 = b1;
    b1 = b0;
  }
  return x * b1 - b2 + c[0];
}

void check_windowed_sinc(const WindowedSincOptions& o) {
  if (o.iterations < 0 || o.iterations > 1000) {
    throw InputError("--smooth", "iterations", "must be in 0..1000, got " + std::to_string(o.iterations));
  }
  if (!(o.pass_band > 0.0 && o.pass_band < 2.0)) throw InputError("--smooth", "pass band", "must be in (0, 2)");
}

}  // namespace

void taubin_smooth(SurfaceMesh& mesh, const TaubinOptions& o) {
  if (o.iterations < 0) throw InputError("--smooth", "iterations", "must be >= 0, got " + std::to_string(o.iterations));
  if (!(o.lambda > 0.0 && o.lambda < 1.0)) throw InputError("--smooth", "lambda", "must be in (0, 1)");
  if (!(o.pass_band > 0.0 && o.pass_band < 1.0 / o.lambda)) {
    throw InputError("--smooth", "pass band", "must be in (0, 1/lambda)");
  }
  if (o.iterations == 0 || mesh.vertex_count() == 0) return;
  const double mu = 1.0 / (o.pass_band - 1.0 / o.lambda);
  const Adjacency adj = one_rings(mesh);
  std::vector<double> x(mesh.vertices.begin(), mesh.vertices.end()), y(x.size());
  for (int it = 0; it < o.iterations; ++it) {
    laplacian_step(adj, o.lambda, x, y);
    laplacian_step(adj, mu, y, x);
  }
  std::transform(x.begin(), x.end(), mesh.vertices.begin(), [](double v) { return static_cast<float>(v); });
  recompute_vertex_normals(mesh);
}

std::vector<double> windowed_sinc_coefficients(const WindowedSincOptions& o) {
  check_windowed_sinc(o);
  const int n = o.iterations;
  const double theta = std::acos(1.0 - 0.5 * o.pass_band), x_pb = 1.0 - 0.5 * o.pass_band;
  const auto g = [&](double sigma) { return chebyshev_sum(hamming_sinc(n, theta + sigma), x_pb) - 1.0; };
  // The smallest sigma in [0, pi - theta] with f(kPB) = 1: scan in steps of a 64th of the
  // polynomial's resolution pi / (N + 1), then bisect the first sign change. None: sigma = 0.
  double sigma = 0.0;
  const double step = std::numbers::pi / (64.0 * (n + 1));
  double lo = 0.0, g_lo = g(0.0);
  for (double hi = step; hi <= std::numbers::pi - theta; hi += step) {
    const double g_hi = g(hi);
    if ((g_hi >= 0.0) != (g_lo >= 0.0)) {
      for (int it = 0; it < 100 && hi - lo > 1e-15; ++it) {
        const double mid = 0.5 * (lo + hi), g_mid = g(mid);
        if ((g_mid >= 0.0) == (g_lo >= 0.0)) {
          lo = mid;
          g_lo = g_mid;
        } else {
          hi = mid;
        }
      }
      sigma = 0.5 * (lo + hi);
      break;
    }
    lo = hi;
    g_lo = g_hi;
  }
  std::vector<double> c = hamming_sinc(n, theta + sigma);
  double sum = 0.0;
  for (const double v : c) sum += v;
  for (double& v : c) v /= sum;
  return c;
}

double windowed_sinc_response(const std::vector<double>& coefficients, double k) {
  return chebyshev_sum(coefficients, 1.0 - 0.5 * k);
}

void windowed_sinc_smooth(SurfaceMesh& mesh, const WindowedSincOptions& o) {
  const std::vector<double> c = windowed_sinc_coefficients(o);
  if (o.iterations == 0 || mesh.vertex_count() == 0) return;
  const Adjacency adj = one_rings(mesh);
  const std::vector<char> border = border_vertices(mesh);
  const auto nv = static_cast<int64_t>(mesh.vertex_count());
  std::vector<double> x0(mesh.vertices.begin(), mesh.vertices.end()), x1(x0.size()), x2(x0.size());
  const std::vector<double> original = x0;
  std::vector<double> out(x0.size());
  half_laplacian_step(adj, x0, x1);
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = c[0] * x0[i] + c[1] * x1[i];
  for (std::size_t it = 2; it < c.size(); ++it) {
    half_laplacian_step(adj, x1, x2);
    const double ci = c[it];
#pragma omp parallel for schedule(static)
    for (int64_t v = 0; v < nv; ++v)
      for (std::size_t a = 0; a < 3; ++a) {
        const std::size_t i = 3 * static_cast<std::size_t>(v) + a;
        x2[i] = 2.0 * x2[i] - x0[i];
        out[i] += ci * x2[i];
      }
    std::swap(x0, x1);
    std::swap(x1, x2);
  }
  for (int64_t v = 0; v < nv; ++v) {
    const auto sv = static_cast<std::size_t>(v);
    const bool fixed = border[sv] || adj.first[sv + 1] == adj.first[sv];
    for (std::size_t a = 0; a < 3; ++a)
      mesh.vertices[3 * sv + a] = static_cast<float>(fixed ? original[3 * sv + a] : out[3 * sv + a]);
  }
  recompute_vertex_normals(mesh);
}

double enclosed_volume_mm3(const SurfaceMesh& mesh) {
  if (mesh.vertex_count() == 0) return 0.0;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (std::size_t v = 0; v < mesh.vertices.size(); v += 3)
    for (Eigen::Index a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], double(mesh.vertices[v + std::size_t(a)]));
      hi[a] = std::max(hi[a], double(mesh.vertices[v + std::size_t(a)]));
    }
  const Eigen::Vector3d o = 0.5 * (lo + hi);
  const auto P = [&](uint32_t v) -> Eigen::Vector3d {
    return Eigen::Vector3d(mesh.vertices[3 * std::size_t{v}], mesh.vertices[3 * std::size_t{v} + 1], mesh.vertices[3 * std::size_t{v} + 2]) - o;
  };
  double vol = 0.0;
  for (std::size_t t = 0; t < mesh.triangles.size(); t += 3)
    vol += P(mesh.triangles[t]).dot(P(mesh.triangles[t + 1]).cross(P(mesh.triangles[t + 2])));
  return vol / 6.0;
}

bool is_closed_oriented_surface(const SurfaceMesh& mesh) {
  std::vector<uint64_t> directed;
  directed.reserve(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); t += 3)
    for (std::size_t c = 0; c < 3; ++c) directed.push_back(uint64_t{mesh.triangles[t + c]} << 32 | mesh.triangles[t + (c + 1) % 3]);
  std::sort(directed.begin(), directed.end());
  if (directed.empty()) return false;
  for (std::size_t i = 0; i < directed.size(); ++i) {
    if (i + 1 < directed.size() && directed[i + 1] == directed[i]) return false;  // an edge used twice one way
    const uint64_t reverse = (directed[i] & 0xffffffffu) << 32 | directed[i] >> 32;
    if (!std::binary_search(directed.begin(), directed.end(), reverse)) return false;
  }
  return true;
}

double restore_enclosed_volume(SurfaceMesh& mesh, double target_mm3) {
  if (!(target_mm3 > 0.0 && std::isfinite(target_mm3))) {
    throw InputError("mesh", "volume", "the target volume must be positive, got " + std::to_string(target_mm3));
  }
  if (!is_closed_oriented_surface(mesh)) {
    throw InputError("mesh", "triangles", "the surface is not closed and consistently oriented: its volume is undefined");
  }
  recompute_vertex_normals(mesh);
  const auto nv = static_cast<std::size_t>(mesh.vertex_count());
  // Positions about the bounding-box centre (the volume does not depend on it; the sums lose less).
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (std::size_t v = 0; v < nv; ++v)
    for (Eigen::Index a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], double(mesh.vertices[3 * v + std::size_t(a)]));
      hi[a] = std::max(hi[a], double(mesh.vertices[3 * v + std::size_t(a)]));
    }
  const Eigen::Vector3d o = 0.5 * (lo + hi);
  std::vector<Eigen::Vector3d> x(nv), n(nv);
  for (std::size_t v = 0; v < nv; ++v) {
    x[v] = Eigen::Vector3d(mesh.vertices[3 * v], mesh.vertices[3 * v + 1], mesh.vertices[3 * v + 2]) - o;
    n[v] = Eigen::Vector3d(mesh.normals[3 * v], mesh.normals[3 * v + 1], mesh.normals[3 * v + 2]);
  }
  // 6 V(t) = sum (a + t na) . ((b + t nb) x (c + t nc)) = q0 + q1 t + q2 t^2 + q3 t^3.
  double q[4] = {0.0, 0.0, 0.0, 0.0};
  for (std::size_t t = 0; t < mesh.triangles.size(); t += 3) {
    const uint32_t i = mesh.triangles[t], j = mesh.triangles[t + 1], k = mesh.triangles[t + 2];
    const Eigen::Vector3d &a = x[i], &b = x[j], &c = x[k], &na = n[i], &nb = n[j], &nc = n[k];
    q[0] += a.dot(b.cross(c));
    q[1] += na.dot(b.cross(c)) + a.dot(nb.cross(c)) + a.dot(b.cross(nc));
    q[2] += na.dot(nb.cross(c)) + na.dot(b.cross(nc)) + a.dot(nb.cross(nc));
    q[3] += na.dot(nb.cross(nc));
  }
  const double target6 = 6.0 * target_mm3;
  double t = 0.0;
  bool converged = false;
  for (int it = 0; it < 50; ++it) {
    const double f = ((q[3] * t + q[2]) * t + q[1]) * t + q[0] - target6;
    if (std::abs(f) <= 1e-12 * target6) {
      converged = true;
      break;
    }
    const double df = (3.0 * q[3] * t + 2.0 * q[2]) * t + q[1];
    if (!(df > 0.0)) break;
    t -= f / df;
  }
  if (!converged) {
    throw RuntimeError("restoring the enclosed volume: no normal offset gives " + std::to_string(target_mm3) + " mm^3");
  }
  const auto write = [&](double offset) {
    for (std::size_t v = 0; v < nv; ++v)
      for (Eigen::Index a = 0; a < 3; ++a)
        mesh.vertices[3 * v + std::size_t(a)] = static_cast<float>(x[v][a] + o[a] + offset * n[v][a]);
  };
  write(t);
  // Float32 rounding moves each vertex by up to half an ulp; correct the volume it changes with the
  // derivative at t (about the area).
  for (int it = 0; it < 3; ++it) {
    const double err = enclosed_volume_mm3(mesh) - target_mm3;
    if (std::abs(err) <= 1e-7 * target_mm3) break;
    t -= 6.0 * err / ((3.0 * q[3] * t + 2.0 * q[2]) * t + q[1]);
    write(t);
  }
  recompute_vertex_normals(mesh);
  return t;
}

void recompute_vertex_normals(SurfaceMesh& mesh) {
  const auto nv = static_cast<std::size_t>(mesh.vertex_count());
  std::vector<double> acc(3 * nv, 0.0);
  const auto P = [&](uint32_t v) {
    return Eigen::Vector3d(mesh.vertices[3 * std::size_t{v}], mesh.vertices[3 * std::size_t{v} + 1], mesh.vertices[3 * std::size_t{v} + 2]);
  };
  for (std::size_t t = 0; t < mesh.triangles.size(); t += 3) {
    const uint32_t id[3] = {mesh.triangles[t], mesh.triangles[t + 1], mesh.triangles[t + 2]};
    const Eigen::Vector3d p[3] = {P(id[0]), P(id[1]), P(id[2])};
    const Eigen::Vector3d n = (p[1] - p[0]).cross(p[2] - p[0]);
    if (!(n.norm() > 0.0)) continue;  // degenerate: no direction to contribute
    const Eigen::Vector3d u = n.normalized();
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector3d e1 = p[(c + 1) % 3] - p[c], e2 = p[(c + 2) % 3] - p[c];
      const double angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
      for (std::size_t a = 0; a < 3; ++a) acc[3 * std::size_t{id[c]} + a] += angle * u[static_cast<Eigen::Index>(a)];
    }
  }
  mesh.normals.resize(3 * nv, 0.0f);
  for (std::size_t v = 0; v < nv; ++v) {
    const Eigen::Vector3d n(acc[3 * v], acc[3 * v + 1], acc[3 * v + 2]);
    if (!(n.norm() > 0.0)) continue;
    const Eigen::Vector3d u = n.normalized();
    for (std::size_t a = 0; a < 3; ++a) mesh.normals[3 * v + a] = static_cast<float>(u[static_cast<Eigen::Index>(a)]);
  }
}

}  // namespace ctsurg
