#include "ctsurg/mesh/normal_map_baking.h"

#include <omp.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "ctsurg/core/error.h"

namespace ctsurg {

namespace {

using Vec3 = Eigen::Vector3d;

struct Barycentric {
  double l[3];
};

// Barycentric coordinates of texel centre (px, py) in the UV triangle t, in texel units.
bool texel_barycentric(const std::vector<float>& uvs, const uint32_t* v, int size, double px, double py, Barycentric& b) {
  const double x0 = uvs[2 * v[0]] * size, y0 = uvs[2 * v[0] + 1] * size;
  const double x1 = uvs[2 * v[1]] * size, y1 = uvs[2 * v[1] + 1] * size;
  const double x2 = uvs[2 * v[2]] * size, y2 = uvs[2 * v[2] + 1] * size;
  const double area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0);
  if (area == 0.0) return false;
  b.l[1] = ((px - x0) * (y2 - y0) - (x2 - x0) * (py - y0)) / area;
  b.l[2] = ((x1 - x0) * (py - y0) - (px - x0) * (y1 - y0)) / area;
  b.l[0] = 1.0 - b.l[1] - b.l[2];
  constexpr double eps = 1e-7;
  return b.l[0] >= -eps && b.l[1] >= -eps && b.l[2] >= -eps;
}

Vec3 any_orthogonal(const Vec3& n) {
  int k = 0;
  for (int a = 1; a < 3; ++a)
    if (std::abs(n[a]) < std::abs(n[k])) k = a;
  return n.cross(Vec3::Unit(k)).normalized();
}

}  // namespace

std::vector<int32_t> texel_owners(const std::vector<float>& uvs, const std::vector<uint32_t>& triangles, int size) {
  std::vector<int32_t> owner(static_cast<std::size_t>(size) * static_cast<std::size_t>(size), -1);
  for (std::size_t t = 0; t < triangles.size() / 3; ++t) {
    const uint32_t* v = &triangles[3 * t];
    double lo_x = 1e300, lo_y = 1e300, hi_x = -1e300, hi_y = -1e300;
    for (int c = 0; c < 3; ++c) {
      lo_x = std::min<double>(lo_x, uvs[2 * v[c]] * size), hi_x = std::max<double>(hi_x, uvs[2 * v[c]] * size);
      lo_y = std::min<double>(lo_y, uvs[2 * v[c] + 1] * size), hi_y = std::max<double>(hi_y, uvs[2 * v[c] + 1] * size);
    }
    const int x0 = std::max(0, static_cast<int>(std::floor(lo_x - 0.5))),
              x1 = std::min(size - 1, static_cast<int>(std::ceil(hi_x - 0.5)));
    const int y0 = std::max(0, static_cast<int>(std::floor(lo_y - 0.5))),
              y1 = std::min(size - 1, static_cast<int>(std::ceil(hi_y - 0.5)));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        int32_t& o = owner[static_cast<std::size_t>(y) * static_cast<std::size_t>(size) + static_cast<std::size_t>(x)];
        Barycentric b{};
        if (o < 0 && texel_barycentric(uvs, v, size, x + 0.5, y + 0.5, b)) o = static_cast<int32_t>(t);
      }
  }
  return owner;
}

NormalMapImage bake_normal_map(const SurfaceMesh& mesh, const DetailField& field, const NormalMapBakeOptions& options,
                               NormalMapBakeStats* stats) {
  const std::size_t nv = static_cast<std::size_t>(mesh.vertex_count());
  if (mesh.uvs.size() != 2 * nv || mesh.tangents.size() != 4 * nv) {
    throw InputError("normal map", "surface", "the surface needs texture coordinates and tangents");
  }
  if (options.size_px < 16 || options.size_px > 16384) throw InputError("normal map", "--size", "must be in 16 .. 16384");
  if (options.bits != 8 && options.bits != 16) throw InputError("normal map", "--bits", "must be 8 or 16");
  if (options.dilate_px < 0 || options.dilate_px > 64) throw InputError("normal map", "--dilate", "must be in 0 .. 64");
  if (!std::isfinite(options.search_mm) || options.search_mm < 0.0) throw InputError("normal map", "--search-mm", "must be >= 0");
  const int size = options.size_px;
  const int threads = options.threads > 0 ? options.threads : omp_get_max_threads();
  const double search = options.search_mm > 0.0 ? options.search_mm : mesh.lattice.spacing.maxCoeff();
  const double step = 0.5 * field.values.geometry.spacing.minCoeff();
  const int steps = std::max(1, static_cast<int>(std::ceil(search / step)));

  const std::vector<int32_t> owner = texel_owners(mesh.uvs, mesh.triangles, size);
  const std::size_t texels = owner.size();
  std::vector<float> normal(3 * texels, 0.0f);  // tangent-space normal per texel
  std::vector<uint8_t> state(texels, 0);        // 0 empty, 1 baked on a crossing, 2 baked otherwise, 3 dilated
  std::vector<float> tilt(texels, 0.0f);

  const auto V = [&](uint32_t v, const std::vector<float>& a, int w) {
    return Vec3(a[static_cast<std::size_t>(w) * v], a[static_cast<std::size_t>(w) * v + 1],
                a[static_cast<std::size_t>(w) * v + 2]);
  };
#pragma omp parallel for schedule(dynamic, 16) num_threads(threads)
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(size) + static_cast<std::size_t>(x);
      if (owner[i] < 0) continue;
      const uint32_t* v = &mesh.triangles[3 * static_cast<std::size_t>(owner[i])];
      Barycentric b{};
      texel_barycentric(mesh.uvs, v, size, x + 0.5, y + 0.5, b);
      double sum = 0.0;
      for (double& l : b.l) sum += (l = std::max(l, 0.0));
      for (double& l : b.l) l /= sum;
      Vec3 P = Vec3::Zero(), N = Vec3::Zero(), T = Vec3::Zero();
      double w = 0.0;
      for (int c = 0; c < 3; ++c) {
        P += b.l[c] * V(v[c], mesh.vertices, 3);
        N += b.l[c] * V(v[c], mesh.normals, 3);
        T += b.l[c] * V(v[c], mesh.tangents, 4);
        w += b.l[c] * mesh.tangents[4 * static_cast<std::size_t>(v[c]) + 3];
      }
      N = N.norm() > 0.0 ? Vec3(N.normalized()) : Vec3::UnitZ();
      T -= N * N.dot(T);
      T = T.norm() > 1e-12 ? Vec3(T.normalized()) : any_orthogonal(N);
      const Vec3 B = (w < 0.0 ? -1.0 : 1.0) * N.cross(T);

      // Nearest crossing of the detailed surface along the normal, from t = 0 outwards.
      const auto f = [&](double t) { return sample_value(field, P + t * N) - field.iso; };
      const double f0 = f(0.0);
      double t_star = 0.0;
      bool found = f0 == 0.0;
      double fp = f0, fm = f0;
      for (int k = 1; k <= steps && !found; ++k) {
        const double tp = k * step, tm = -k * step;
        const double gp = f(tp), gm = f(tm);
        double best = 1e300;
        const auto refine = [&](double a, double fa, double c, double fc) {
          for (int it = 0; it < 3; ++it) {  // regula falsi, keeping the bracket
            const double m = a - fa * (c - a) / (fc - fa), fmid = f(m);
            if (fmid == 0.0) return m;
            if ((fmid < 0.0) == (fa < 0.0))
              a = m, fa = fmid;
            else
              c = m, fc = fmid;
          }
          return a - fa * (c - a) / (fc - fa);
        };
        if ((gp < 0.0) != (fp < 0.0) || gp == 0.0) {
          const double r = refine(tp - step, fp, tp, gp);
          if (std::abs(r) < best) best = std::abs(r), t_star = r;
          found = true;
        }
        if ((gm < 0.0) != (fm < 0.0) || gm == 0.0) {
          const double r = refine(tm + step, fm, tm, gm);
          if (std::abs(r) < best) best = std::abs(r), t_star = r;
          found = true;
        }
        fp = gp, fm = gm;
      }
      Vec3 g = sample_gradient(field, P + t_star * N);
      if (!found || g.norm() < 1e-12) g = sample_gradient(field, P);
      const Vec3 n = g.norm() > 1e-12 ? Vec3(-g.normalized()) : N;
      const Vec3 ts(n.dot(T), n.dot(B), n.dot(N));
      for (int c = 0; c < 3; ++c) normal[3 * i + static_cast<std::size_t>(c)] = static_cast<float>(ts[c]);
      state[i] = found ? 1 : 2;
      tilt[i] = static_cast<float>(std::acos(std::clamp(ts.z(), -1.0, 1.0)) * 180.0 / std::numbers::pi);
    }
  }

  // Dilation into the padding.
  for (int pass = 0; pass < options.dilate_px; ++pass) {
    const std::vector<uint8_t> before = state;
    const std::vector<float> normal_before = normal;
#pragma omp parallel for schedule(static) num_threads(threads)
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(size) + static_cast<std::size_t>(x);
        if (before[i] != 0) continue;
        Vec3 s = Vec3::Zero();
        int count = 0;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int xx = x + dx, yy = y + dy;
            if (xx < 0 || yy < 0 || xx >= size || yy >= size) continue;
            const std::size_t j = static_cast<std::size_t>(yy) * static_cast<std::size_t>(size) + static_cast<std::size_t>(xx);
            if (before[j] == 0) continue;
            s += Vec3(normal_before[3 * j], normal_before[3 * j + 1], normal_before[3 * j + 2]);
            ++count;
          }
        if (count == 0 || s.norm() < 1e-12) continue;
        s.normalize();
        for (int c = 0; c < 3; ++c) normal[3 * i + static_cast<std::size_t>(c)] = static_cast<float>(s[c]);
        state[i] = 3;
      }
  }

  NormalMapImage img;
  img.width = img.height = size;
  img.bits = options.bits;
  img.rgb.resize(3 * texels);
  const double maxv = static_cast<double>((1 << options.bits) - 1);
  for (std::size_t i = 0; i < texels; ++i) {
    const Vec3 n = state[i] == 0 ? Vec3::UnitZ() : Vec3(normal[3 * i], normal[3 * i + 1], normal[3 * i + 2]);
    for (int c = 0; c < 3; ++c) {
      img.rgb[3 * i + static_cast<std::size_t>(c)] =
          static_cast<uint16_t>(std::clamp(std::lround((n[c] + 1.0) * 0.5 * maxv), 0L, static_cast<long>(maxv)));
    }
  }
  if (stats) {
    *stats = {};
    stats->search_mm = search;
    double tilt_sum = 0.0;
    for (std::size_t i = 0; i < texels; ++i) {
      if (state[i] == 1 || state[i] == 2) ++stats->texels_covered, tilt_sum += tilt[i];
      if (state[i] == 1) ++stats->texels_on_crossing;
      if (state[i] == 3) ++stats->texels_dilated;
    }
    stats->mean_tilt_deg = stats->texels_covered ? tilt_sum / static_cast<double>(stats->texels_covered) : 0.0;
  }
  return img;
}

Eigen::Vector3d decode_normal_map_texel(const NormalMapImage& map, int64_t x, int64_t y) {
  const double maxv = static_cast<double>((1 << map.bits) - 1);
  const std::size_t i = 3 * static_cast<std::size_t>(y * map.width + x);
  const Vec3 n(map.rgb[i] / maxv * 2.0 - 1.0, map.rgb[i + 1] / maxv * 2.0 - 1.0, map.rgb[i + 2] / maxv * 2.0 - 1.0);
  return n.norm() > 0.0 ? Vec3(n.normalized()) : Vec3::UnitZ();
}

}  // namespace ctsurg
