#include "ctsurg/mesh/tet_mesh_quality.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace ctsurg {

double tet_signed_volume(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& p2,
                         const Eigen::Vector3d& p3) {
  return (p1 - p0).dot((p2 - p0).cross(p3 - p0)) / 6.0;
}

std::array<double, 6> tet_dihedral_angles_deg(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                                              const Eigen::Vector3d& p2, const Eigen::Vector3d& p3) {
  const std::array<Eigen::Vector3d, 4> p{p0, p1, p2, p3};
  // Face f is opposite vertex f; its normal is made to point away from vertex f (outward).
  std::array<Eigen::Vector3d, 4> n;
  for (int f = 0; f < 4; ++f) {
    const Eigen::Vector3d& a = p[static_cast<std::size_t>((f + 1) % 4)];
    const Eigen::Vector3d& b = p[static_cast<std::size_t>((f + 2) % 4)];
    const Eigen::Vector3d& c = p[static_cast<std::size_t>((f + 3) % 4)];
    Eigen::Vector3d m = (b - a).cross(c - a);
    if (m.dot(p[static_cast<std::size_t>(f)] - a) > 0.0) m = -m;
    const double len = m.norm();
    n[static_cast<std::size_t>(f)] = len > 0.0 ? Eigen::Vector3d(m / len) : Eigen::Vector3d::Zero();
  }
  // Edge (a, b) is shared by the faces opposite the two other vertices (c, d).
  constexpr int edges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  std::array<double, 6> out{};
  for (int e = 0; e < 6; ++e) {
    int c = -1, d = -1;
    for (int v = 0; v < 4; ++v) {
      if (v == edges[e][0] || v == edges[e][1]) continue;
      (c < 0 ? c : d) = v;
    }
    const Eigen::Vector3d& nc = n[static_cast<std::size_t>(c)];
    const Eigen::Vector3d& nd = n[static_cast<std::size_t>(d)];
    if (nc.isZero() || nd.isZero()) continue;  // degenerate: 0
    const double cosang = std::clamp(nc.dot(nd), -1.0, 1.0);
    out[static_cast<std::size_t>(e)] = 180.0 - std::acos(cosang) * 180.0 / std::numbers::pi;
  }
  return out;
}

double tet_radius_edge_ratio(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& p2,
                             const Eigen::Vector3d& p3) {
  // Circumcentre relative to p0: solves 2 [a b c]^T x = (|a|^2, |b|^2, |c|^2) for edge vectors a, b, c.
  const Eigen::Vector3d a = p1 - p0, b = p2 - p0, c = p3 - p0;
  const double det = 2.0 * a.dot(b.cross(c));
  double lmin2 = std::min({a.squaredNorm(), b.squaredNorm(), c.squaredNorm(), (p2 - p1).squaredNorm(),
                           (p3 - p1).squaredNorm(), (p3 - p2).squaredNorm()});
  if (det == 0.0 || lmin2 == 0.0) return std::numeric_limits<double>::infinity();
  const Eigen::Vector3d x =
      (a.squaredNorm() * b.cross(c) + b.squaredNorm() * c.cross(a) + c.squaredNorm() * a.cross(b)) / det;
  return x.norm() / std::sqrt(lmin2);
}

TetMeshQuality tet_mesh_quality(const std::vector<double>& nodes, const std::vector<int32_t>& tets,
                                double sliver_threshold_deg) {
  TetMeshQuality q;
  q.sliver_threshold_deg = sliver_threshold_deg;
  for (int b = 0; b <= 15; ++b) q.radius_edge_bin_edges.push_back(0.6 + 0.1 * b);
  q.radius_edge_histogram.assign(q.radius_edge_bin_edges.size() - 1, 0);
  const std::size_t nt = tets.size() / 4;
  if (nt == 0) return q;
  const auto node = [&](int32_t i) {
    const auto k = static_cast<std::size_t>(i);
    return Eigen::Vector3d(nodes[3 * k], nodes[3 * k + 1], nodes[3 * k + 2]);
  };
  q.min_dihedral_deg = 180.0;
  q.max_dihedral_deg = 0.0;
  q.min_radius_edge = std::numeric_limits<double>::infinity();
  double sum_re = 0.0;
  for (std::size_t t = 0; t < nt; ++t) {
    const Eigen::Vector3d p0 = node(tets[4 * t]), p1 = node(tets[4 * t + 1]), p2 = node(tets[4 * t + 2]),
                          p3 = node(tets[4 * t + 3]);
    const double v = tet_signed_volume(p0, p1, p2, p3);
    q.volume_mm3 += v;
    if (!(v > 0.0)) ++q.inverted;
    const auto ang = tet_dihedral_angles_deg(p0, p1, p2, p3);
    const auto [lo, hi] = std::minmax_element(ang.begin(), ang.end());
    q.min_dihedral_deg = std::min(q.min_dihedral_deg, *lo);
    q.max_dihedral_deg = std::max(q.max_dihedral_deg, *hi);
    if (*lo < sliver_threshold_deg) ++q.slivers;
    const double re = tet_radius_edge_ratio(p0, p1, p2, p3);
    q.min_radius_edge = std::min(q.min_radius_edge, re);
    q.max_radius_edge = std::max(q.max_radius_edge, re);
    sum_re += re;
    // Bin by the edges; below the first edge counts in the first bin, above the last in the last.
    const auto it = std::upper_bound(q.radius_edge_bin_edges.begin(), q.radius_edge_bin_edges.end(), re);
    const auto bin = std::clamp<std::ptrdiff_t>(it - q.radius_edge_bin_edges.begin() - 1, 0,
                                                static_cast<std::ptrdiff_t>(q.radius_edge_histogram.size()) - 1);
    ++q.radius_edge_histogram[static_cast<std::size_t>(bin)];
  }
  q.mean_radius_edge = sum_re / static_cast<double>(nt);
  return q;
}

}  // namespace ctsurg
