#include "ctsurg/mesh/detail_field.h"

#include <omp.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "ctsurg/core/error.h"

namespace ctsurg {

namespace {

DetailField make_field(Volume<float> values, double iso) {
  DetailField f;
  f.iso = iso;
  f.world_to_index_linear = values.geometry.index_to_world_matrix().inverse();
  f.values = std::move(values);
  return f;
}

// Fractional index of p, clamped into the lattice; cell corner (i0, j0, k0) and weights.
struct Cell {
  int64_t i[3];
  double t[3];
};
Cell locate(const DetailField& f, const Eigen::Vector3d& p) {
  const auto& g = f.values.geometry;
  const Eigen::Vector3d x = f.world_to_index_linear * (p - g.origin);
  Cell c{};
  for (int a = 0; a < 3; ++a) {
    const int64_t n = g.dims[static_cast<std::size_t>(a)];
    const double xa = std::clamp(x[a], 0.0, static_cast<double>(n - 1));
    const int64_t i0 = std::min<int64_t>(static_cast<int64_t>(std::floor(xa)), std::max<int64_t>(n - 2, 0));
    c.i[a] = i0;
    c.t[a] = n > 1 ? xa - static_cast<double>(i0) : 0.0;
  }
  return c;
}

}  // namespace

Volume<float> gaussian_smoothed(const Volume<float>& field, double sigma_mm, int threads) {
  if (!std::isfinite(sigma_mm) || sigma_mm < 0.0) throw InputError("--sigma-mm", "", "must be a finite number >= 0");
  const auto& g = field.geometry;
  double extent = 0.0;
  for (int a = 0; a < 3; ++a) extent = std::max(extent, g.spacing[a] * static_cast<double>(g.dims[static_cast<std::size_t>(a)]));
  if (sigma_mm > extent) {
    throw InputError("--sigma-mm", "",
                     std::to_string(sigma_mm) + " mm is wider than the whole field (" + std::to_string(extent) +
                         " mm): it would smooth it flat; use at most that");
  }
  Volume<float> out = field;
  if (sigma_mm == 0.0) return out;
  const int64_t nx = g.dims[0], ny = g.dims[1];
  const int64_t stride[3] = {1, nx, nx * ny};
  Volume<float> tmp = field;
  for (int a = 0; a < 3; ++a) {
    const double s = sigma_mm / g.spacing[a];
    // Beyond the line's length every tap reads the clamped edge: no wider kernel is needed.
    const double line = static_cast<double>(g.dims[static_cast<std::size_t>(a)]);
    const int r = static_cast<int>(std::min(std::ceil(3.0 * s), line));
    if (r == 0) continue;
    std::vector<double> kernel(static_cast<std::size_t>(2 * r + 1));
    double sum = 0.0;
    for (int k = -r; k <= r; ++k) sum += kernel[static_cast<std::size_t>(k + r)] = std::exp(-0.5 * k * k / (s * s));
    for (double& k : kernel) k /= sum;
    const int64_t n = g.dims[static_cast<std::size_t>(a)];
    const int64_t lines = g.voxel_count() / n;
    const std::vector<float>& src = out.voxels;
    std::vector<float>& dst = tmp.voxels;
#pragma omp parallel for schedule(static) num_threads(threads > 0 ? threads : omp_get_max_threads())
    for (int64_t l = 0; l < lines; ++l) {
      // Start of line l: the other two indices enumerated with the lower axis fastest.
      int64_t base = 0;
      if (a == 0)
        base = l * nx;
      else if (a == 1)
        base = (l % nx) + (l / nx) * nx * ny;
      else
        base = l;
      for (int64_t i = 0; i < n; ++i) {
        double acc = 0.0;
        for (int k = -r; k <= r; ++k) {
          const int64_t j = std::clamp<int64_t>(i + k, 0, n - 1);
          acc += kernel[static_cast<std::size_t>(k + r)] * src[static_cast<std::size_t>(base + j * stride[a])];
        }
        dst[static_cast<std::size_t>(base + i * stride[a])] = static_cast<float>(acc);
      }
    }
    std::swap(out.voxels, tmp.voxels);  // the result of this axis is the input of the next
  }
  return out;
}

DetailField detail_field_from_labels(const Volume<uint16_t>& labels, double sigma_mm, int threads) {
  Volume<float> indicator(labels.geometry, 0.0f);
  for (std::size_t i = 0; i < labels.voxels.size(); ++i) indicator.voxels[i] = labels.voxels[i] != 0 ? 1.0f : 0.0f;
  return make_field(gaussian_smoothed(indicator, sigma_mm, threads), 0.5);
}

DetailField detail_field_from_anti_aliased_labels(const Volume<uint16_t>& labels, const AntiAliasOptions& options,
                                                  AntiAliasStats* stats) {
  return make_field(anti_aliased_mask(labels, options, stats), 0.0);
}

DetailField detail_field_from_values(const Volume<float>& values, double iso, double sigma_mm, int threads) {
  if (!std::isfinite(iso)) throw InputError("--iso", "", "must be a finite number");
  return make_field(gaussian_smoothed(values, sigma_mm, threads), iso);
}

// Calls fn(w, i, j, k) for the 8 corner nodes of the cell holding `c` with their trilinear weights
// (nodes past the last one clamped to it; zero weights skipped).
template <class Fn>
void for_each_corner(const Cell& c, const ImageGeometry& g, Fn&& fn) {
  for (int corner = 0; corner < 8; ++corner) {
    double w = 1.0;
    int64_t idx[3];
    for (int a = 0; a < 3; ++a) {
      const int bit = (corner >> a) & 1;
      idx[a] = std::min(c.i[a] + bit, g.dims[static_cast<std::size_t>(a)] - 1);
      w *= bit ? c.t[a] : 1.0 - c.t[a];
    }
    if (w != 0.0) fn(w, idx);
  }
}

double sample_value(const DetailField& f, const Eigen::Vector3d& p) {
  double v = 0.0;
  for_each_corner(locate(f, p), f.values.geometry, [&](double w, const int64_t* idx) { v += w * f.values(idx[0], idx[1], idx[2]); });
  return v;
}

Eigen::Vector3d sample_gradient(const DetailField& f, const Eigen::Vector3d& p) {
  const auto& g = f.values.geometry;
  Eigen::Vector3d grad_index = Eigen::Vector3d::Zero();
  for_each_corner(locate(f, p), g, [&](double w, const int64_t* idx) {
    for (int a = 0; a < 3; ++a) {
      int64_t lo[3] = {idx[0], idx[1], idx[2]}, hi[3] = {idx[0], idx[1], idx[2]};
      lo[a] = std::max<int64_t>(idx[a] - 1, 0);
      hi[a] = std::min<int64_t>(idx[a] + 1, g.dims[static_cast<std::size_t>(a)] - 1);
      if (hi[a] == lo[a]) continue;
      grad_index[a] += w * (f.values(hi[0], hi[1], hi[2]) - f.values(lo[0], lo[1], lo[2])) / static_cast<double>(hi[a] - lo[a]);
    }
  });
  // d f / d world = M^{-T} d f / d index, M the index-to-world matrix.
  return f.world_to_index_linear.transpose() * grad_index;
}

}  // namespace ctsurg
