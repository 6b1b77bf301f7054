#include "ctsurg/sim/surface/tet_embedding.h"

#include "ctsurg/core/error.h"

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace ctsurg::sim {

namespace {

// Barycentric coordinates of p in tet t (4 values summing to 1).
std::array<double, 4> barycentric(const TetMesh& m, int64_t t, const Eigen::Vector3d& p) {
  const int32_t* v = &m.tets[static_cast<size_t>(4 * t)];
  const auto node = [&](int a) { return Eigen::Vector3d(m.nodes[static_cast<size_t>(3 * v[a])], m.nodes[static_cast<size_t>(3 * v[a] + 1)],
                                                        m.nodes[static_cast<size_t>(3 * v[a] + 2)]); };
  Eigen::Matrix3d e;
  e.col(0) = node(1) - node(0);
  e.col(1) = node(2) - node(0);
  e.col(2) = node(3) - node(0);
  const Eigen::Vector3d l = e.fullPivLu().solve(p - node(0));
  return {1 - l.sum(), l[0], l[1], l[2]};
}

}  // namespace

SurfaceCoupling embed_surface_in_tets(const std::vector<float>& vertices, const TetMesh& mesh, double max_distance_mm,
                                      TetEmbeddingStats* stats) {
  const int64_t nt = mesh.tet_count(), nv = static_cast<int64_t>(vertices.size() / 3);
  if (nt == 0) throw InputError("tetmesh", "/tetmesh/tets", "empty mesh");
  // Bucket grid over the mesh's bounding box.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = Eigen::Vector3d::Constant(-1e300);
  for (int64_t i = 0; i < mesh.node_count(); ++i) {
    for (int c = 0; c < 3; ++c) {
      lo[c] = std::min(lo[c], mesh.nodes[static_cast<size_t>(3 * i + c)]);
      hi[c] = std::max(hi[c], mesh.nodes[static_cast<size_t>(3 * i + c)]);
    }
  }
  double edge_sum = 0;
  for (int64_t t = 0; t < nt; ++t) {
    const int32_t a = mesh.tets[static_cast<size_t>(4 * t)], b = mesh.tets[static_cast<size_t>(4 * t + 1)];
    double d2 = 0;
    for (int c = 0; c < 3; ++c) {
      const double d = mesh.nodes[static_cast<size_t>(3 * a + c)] - mesh.nodes[static_cast<size_t>(3 * b + c)];
      d2 += d * d;
    }
    edge_sum += std::sqrt(d2);
  }
  const double cell = std::max(edge_sum / static_cast<double>(nt), 1e-6);
  std::array<int64_t, 3> dims{};
  for (int c = 0; c < 3; ++c) dims[static_cast<size_t>(c)] = std::max<int64_t>(1, static_cast<int64_t>(std::ceil((hi[c] - lo[c]) / cell)));
  const auto bucket_of = [&](const Eigen::Vector3d& p, int c) {
    return std::clamp<int64_t>(static_cast<int64_t>(std::floor((p[c] - lo[c]) / cell)), 0, dims[static_cast<size_t>(c)] - 1);
  };
  const int64_t nb = dims[0] * dims[1] * dims[2];
  std::vector<int64_t> start(static_cast<size_t>(nb + 1), 0);
  std::vector<int32_t> entries;
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<int64_t> fill = start;
    for (int64_t t = 0; t < nt; ++t) {
      Eigen::Vector3d a = Eigen::Vector3d::Constant(1e300), b = Eigen::Vector3d::Constant(-1e300);
      for (int k = 0; k < 4; ++k) {
        const int32_t n = mesh.tets[static_cast<size_t>(4 * t + k)];
        for (int c = 0; c < 3; ++c) {
          a[c] = std::min(a[c], mesh.nodes[static_cast<size_t>(3 * n + c)]);
          b[c] = std::max(b[c], mesh.nodes[static_cast<size_t>(3 * n + c)]);
        }
      }
      for (int64_t k = bucket_of(a, 2); k <= bucket_of(b, 2); ++k) {
        for (int64_t j = bucket_of(a, 1); j <= bucket_of(b, 1); ++j) {
          for (int64_t i = bucket_of(a, 0); i <= bucket_of(b, 0); ++i) {
            const int64_t id = i + dims[0] * (j + dims[1] * k);
            if (pass == 0) {
              ++start[static_cast<size_t>(id + 1)];
            } else {
              entries[static_cast<size_t>(fill[static_cast<size_t>(id)]++)] = static_cast<int32_t>(t);
            }
          }
        }
      }
    }
    if (pass == 0) {
      for (int64_t b = 0; b < nb; ++b) start[static_cast<size_t>(b + 1)] += start[static_cast<size_t>(b)];
      entries.resize(static_cast<size_t>(start.back()));
    }
  }

  SurfaceCoupling out;
  out.mode = CouplingMode::trilinear;
  out.particles.assign(static_cast<size_t>(8 * nv), -1);
  out.weights.assign(static_cast<size_t>(8 * nv), 0);
  out.rest_vertices.assign(vertices.begin(), vertices.end());
  TetEmbeddingStats st;
  const int64_t max_ring = std::max<int64_t>(1, static_cast<int64_t>(std::ceil(max_distance_mm / cell)) + 1);
  for (int64_t v = 0; v < nv; ++v) {
    const Eigen::Vector3d p(vertices[static_cast<size_t>(3 * v)], vertices[static_cast<size_t>(3 * v + 1)],
                            vertices[static_cast<size_t>(3 * v + 2)]);
    const int64_t ci = bucket_of(p, 0), cj = bucket_of(p, 1), ck = bucket_of(p, 2);
    int64_t best = -1;
    double best_min = -std::numeric_limits<double>::infinity();
    std::array<double, 4> best_w{};
    // Rings of buckets around the vertex's, until a containing tet is found or a ring beyond the
    // best candidate's distance has been searched.
    for (int64_t ring = 0; ring <= max_ring; ++ring) {
      for (int64_t k = ck - ring; k <= ck + ring; ++k) {
        for (int64_t j = cj - ring; j <= cj + ring; ++j) {
          for (int64_t i = ci - ring; i <= ci + ring; ++i) {
            if (std::max({std::abs(i - ci), std::abs(j - cj), std::abs(k - ck)}) != ring) continue;
            if (i < 0 || j < 0 || k < 0 || i >= dims[0] || j >= dims[1] || k >= dims[2]) continue;
            const int64_t id = i + dims[0] * (j + dims[1] * k);
            for (int64_t e = start[static_cast<size_t>(id)]; e < start[static_cast<size_t>(id + 1)]; ++e) {
              const int32_t t = entries[static_cast<size_t>(e)];
              const auto w = barycentric(mesh, t, p);
              const double mn = *std::min_element(w.begin(), w.end());
              if (mn > best_min || (mn == best_min && t < best)) {
                best_min = mn;
                best = t;
                best_w = w;
              }
            }
          }
        }
      }
      if (best >= 0 && best_min >= -1e-9) break;
      if (best >= 0 && ring >= 2) break;  // two rings past the vertex's bucket: the nearest tet is among them
    }
    if (best < 0) {
      throw InputError("surface", "vertex " + std::to_string(v), "farther than " + std::to_string(max_distance_mm) + " mm from every tet");
    }
    if (best_min >= -1e-9) {
      ++st.inside;
    } else {
      // Clamp and renormalise; distance estimate: the defect times the tet's size.
      ++st.outside;
      const double dist = -best_min * cell;
      if (dist > max_distance_mm) {
        throw InputError("surface", "vertex " + std::to_string(v),
                         "about " + std::to_string(dist) + " mm outside the tet mesh (more than " + std::to_string(max_distance_mm) +
                             " mm): is it the same organ?");
      }
      st.max_outside_mm = std::max(st.max_outside_mm, dist);
      double sum = 0;
      for (auto& w : best_w) sum += (w = std::max(w, 0.0));
      for (auto& w : best_w) w /= sum;
    }
    for (int k = 0; k < 4; ++k) {
      out.particles[static_cast<size_t>(8 * v + k)] = mesh.tets[static_cast<size_t>(4 * best + k)];
      out.weights[static_cast<size_t>(8 * v + k)] = static_cast<Real>(best_w[static_cast<size_t>(k)]);
    }
  }
  if (stats) *stats = st;
  return out;
}

}  // namespace ctsurg::sim
