#include "ctsurg/mesh/surface_smoothing.h"

#include "ctsurg/core/error.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
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
