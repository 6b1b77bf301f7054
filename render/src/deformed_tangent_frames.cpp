#include "ctsurg/render/deformed_tangent_frames.h"

#include <Eigen/Geometry>

#include <cmath>

#include "ctsurg/core/error.h"

namespace ctsurg {

namespace {

using Vec3 = Eigen::Vector3d;

Vec3 at(const float* a, std::size_t i) { return Vec3(a[3 * i], a[3 * i + 1], a[3 * i + 2]); }

// Orthonormal frame [t, g x t, g] as columns; false when g or t (after Gram-Schmidt) vanishes.
bool frame(const Vec3& g_sum, const Vec3& t_sum, Eigen::Matrix3d& f) {
  const double gn = g_sum.norm();
  if (!(gn > 0.0)) return false;
  const Vec3 g = g_sum / gn;
  const Vec3 t_perp = t_sum - g * g.dot(t_sum);
  const double tn = t_perp.norm();
  if (!(tn > 1e-12 * std::max(1.0, t_sum.norm()))) return false;
  const Vec3 t = t_perp / tn;
  f.col(0) = t;
  f.col(1) = g.cross(t);
  f.col(2) = g;
  return true;
}

}  // namespace

DeformedTangentFrames::DeformedTangentFrames(const SurfaceMesh& rest)
    : vertex_count_(rest.vertex_count()),
      rest_vertices_(rest.vertices),
      rest_normals_(rest.normals),
      rest_tangents_(rest.tangents),
      uvs_(rest.uvs) {
  if (rest_normals_.size() != rest_vertices_.size())
    throw InputError("surface", "/surface/normals", "the renderer needs one normal per vertex");
  if (!rest_tangents_.empty() && rest_tangents_.size() != 4 * static_cast<std::size_t>(vertex_count_))
    throw InputError("surface", "/surface/tangents", "one tangent per vertex expected");
  if (!uvs_.empty() && uvs_.size() != 2 * static_cast<std::size_t>(vertex_count_))
    throw InputError("surface", "/surface/uvs", "one uv per vertex expected");
  // Seam groups: every copy of a source vertex points at the first copy.
  weld_.resize(static_cast<std::size_t>(vertex_count_));
  if (rest.source_vertex.size() == weld_.size() && rest.source_vertex_count > 0) {
    std::vector<int64_t> first(static_cast<std::size_t>(rest.source_vertex_count), -1);
    for (std::size_t v = 0; v < weld_.size(); ++v) {
      int64_t& f = first[rest.source_vertex[v]];
      if (f < 0) f = static_cast<int64_t>(v);
      weld_[v] = static_cast<uint32_t>(f);
    }
  } else {
    for (std::size_t v = 0; v < weld_.size(); ++v) weld_[v] = static_cast<uint32_t>(v);
  }
}

DeformedTangentFrames::GeometricFrames DeformedTangentFrames::geometric_frames(const float* p,
                                                                               const std::vector<uint32_t>& tri) const {
  GeometricFrames out;
  const std::size_t nv = static_cast<std::size_t>(vertex_count_);
  std::vector<double> g(3 * nv, 0.0), t;
  const bool with_uv = !uvs_.empty();
  if (with_uv) t.assign(3 * nv, 0.0);
  for (std::size_t f = 0; f + 2 < tri.size(); f += 3) {
    const uint32_t i0 = tri[f], i1 = tri[f + 1], i2 = tri[f + 2];
    const Vec3 p0 = at(p, i0), e1 = at(p, i1) - p0, e2 = at(p, i2) - p0;
    const Vec3 n = e1.cross(e2);  // twice the area times the unit normal: area weighting
    for (const uint32_t v : {i0, i1, i2})
      for (int c = 0; c < 3; ++c) g[3 * weld_[v] + c] += n[c];
    if (with_uv) {
      const double du1 = uvs_[2 * i1] - uvs_[2 * i0], dv1 = uvs_[2 * i1 + 1] - uvs_[2 * i0 + 1];
      const double du2 = uvs_[2 * i2] - uvs_[2 * i0], dv2 = uvs_[2 * i2 + 1] - uvs_[2 * i0 + 1];
      const double r = du1 * dv2 - du2 * dv1;
      if (std::abs(r) < 1e-14) continue;
      const Vec3 dpdu = (e1 * dv2 - e2 * dv1) / r;
      const double len = dpdu.norm();
      if (!(len > 0.0)) continue;
      // Weighted by area, like g, so that large triangles dominate the same way in both frames.
      const Vec3 w = dpdu / len * (0.5 * n.norm());
      for (const uint32_t v : {i0, i1, i2})
        for (int c = 0; c < 3; ++c) t[3 * v + c] += w[c];
    }
  }
  out.g.resize(3 * nv);
  for (std::size_t v = 0; v < nv; ++v)
    for (int c = 0; c < 3; ++c) out.g[3 * v + c] = static_cast<float>(g[3 * weld_[v] + c]);
  out.t.assign(t.begin(), t.end());
  return out;
}

void DeformedTangentFrames::compute(const float* vertices, const std::vector<uint32_t>& triangles, int topology,
                                    std::vector<float>& normals, std::vector<float>& tangents) {
  auto it = rest_cache_.find(topology);
  if (it == rest_cache_.end()) it = rest_cache_.emplace(topology, geometric_frames(rest_vertices_.data(), triangles)).first;
  const GeometricFrames& rest = it->second;
  const GeometricFrames now = geometric_frames(vertices, triangles);
  const std::size_t nv = static_cast<std::size_t>(vertex_count_);
  const bool with_tangents = !rest_tangents_.empty();
  normals.resize(3 * nv);
  tangents.resize(with_tangents ? 4 * nv : 0);
  for (std::size_t v = 0; v < nv; ++v) {
    const Vec3 g0 = at(rest.g.data(), v), g1 = at(now.g.data(), v);
    Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
    Eigen::Matrix3d f0, f1;
    if (!rest.t.empty() && frame(g0, at(rest.t.data(), v), f0) && frame(g1, at(now.t.data(), v), f1)) {
      r = f1 * f0.transpose();
    } else if (g0.norm() > 0.0 && g1.norm() > 0.0) {
      r = Eigen::Quaterniond::FromTwoVectors(g0, g1).toRotationMatrix();
    }
    const Vec3 n = (r * at(rest_normals_.data(), v)).normalized();
    for (int c = 0; c < 3; ++c) normals[3 * v + c] = static_cast<float>(n[c]);
    if (with_tangents) {
      const Vec3 t0(rest_tangents_[4 * v], rest_tangents_[4 * v + 1], rest_tangents_[4 * v + 2]);
      Vec3 t = r * t0;
      t = (t - n * n.dot(t));
      const double tn = t.norm();
      t = tn > 0.0 ? Vec3(t / tn) : n.unitOrthogonal();
      for (int c = 0; c < 3; ++c) tangents[4 * v + c] = static_cast<float>(t[c]);
      tangents[4 * v + 3] = rest_tangents_[4 * v + 3];
    }
  }
}

}  // namespace ctsurg
