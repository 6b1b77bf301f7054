#include "ctsurg/mesh/tangent_frames.h"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "ctsurg/core/error.h"

namespace ctsurg {

std::vector<float> tangent_frames(const std::vector<float>& vertices, const std::vector<float>& normals,
                                  const std::vector<uint32_t>& triangles, const std::vector<float>& uvs) {
  using Vec3 = Eigen::Vector3d;
  const std::size_t nv = vertices.size() / 3;
  if (vertices.size() % 3 != 0 || normals.size() != 3 * nv || uvs.size() != 2 * nv || triangles.size() % 3 != 0) {
    throw InputError("tangent frames", "arrays", "vertices, normals and uvs must describe the same vertices");
  }
  for (const uint32_t t : triangles)
    if (t >= nv) throw InputError("tangent frames", "triangles", "vertex index out of range");
  const auto P = [&](uint32_t v) { return Vec3(vertices[3 * v], vertices[3 * v + 1], vertices[3 * v + 2]); };
  std::vector<Vec3> du_sum(nv, Vec3::Zero()), dv_sum(nv, Vec3::Zero());
  for (std::size_t t = 0; t < triangles.size(); t += 3) {
    const uint32_t v[3] = {triangles[t], triangles[t + 1], triangles[t + 2]};
    const Vec3 e1 = P(v[1]) - P(v[0]), e2 = P(v[2]) - P(v[0]);
    const double du1 = uvs[2 * v[1]] - uvs[2 * v[0]], dv1 = uvs[2 * v[1] + 1] - uvs[2 * v[0] + 1];
    const double du2 = uvs[2 * v[2]] - uvs[2 * v[0]], dv2 = uvs[2 * v[2] + 1] - uvs[2 * v[0] + 1];
    const double r = du1 * dv2 - du2 * dv1;
    if (std::abs(r) < 1e-20 || e1.cross(e2).squaredNorm() < 1e-30) continue;
    const Vec3 dpdu = (e1 * dv2 - e2 * dv1) / r, dpdv = (e2 * du1 - e1 * du2) / r;
    if (dpdu.squaredNorm() == 0.0 || dpdv.squaredNorm() == 0.0) continue;
    const Vec3 tu = dpdu.normalized(), tv = dpdv.normalized();
    for (int c = 0; c < 3; ++c) {
      const Vec3 a = P(v[(c + 1) % 3]) - P(v[c]), b = P(v[(c + 2) % 3]) - P(v[c]);
      const double angle = std::atan2(a.cross(b).norm(), a.dot(b));
      du_sum[v[c]] += angle * tu;
      dv_sum[v[c]] += angle * tv;
    }
  }
  std::vector<float> out(4 * nv);
  for (std::size_t i = 0; i < nv; ++i) {
    Vec3 n(normals[3 * i], normals[3 * i + 1], normals[3 * i + 2]);
    n = n.norm() > 0.0 ? Vec3(n.normalized()) : Vec3(0.0, 0.0, 1.0);
    Vec3 t = du_sum[i] - n * n.dot(du_sum[i]);
    double w = 1.0;
    if (t.norm() > 1e-12) {
      t.normalize();
      w = n.cross(t).dot(-dv_sum[i]) < 0.0 ? -1.0 : 1.0;
    } else {
      // Any unit vector orthogonal to n: cross with the axis least aligned with it.
      int k = 0;
      for (int a = 1; a < 3; ++a)
        if (std::abs(n[a]) < std::abs(n[k])) k = a;
      t = n.cross(Vec3::Unit(k)).normalized();
    }
    for (int c = 0; c < 3; ++c) out[4 * i + static_cast<std::size_t>(c)] = static_cast<float>(t[c]);
    out[4 * i + 3] = static_cast<float>(w);
  }
  return out;
}

}  // namespace ctsurg
