#include "ctsurg/mesh/anti_aliased_mask.h"

#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <numeric>
#include <string>
#include <vector>

#include "ctsurg/core/error.h"

namespace ctsurg {

namespace {

constexpr int64_t kSumBlock = 4096;  // fixed blocks: sums and maxima independent of the thread count

// Separable Gaussian (standard deviation sigma_vox[a] voxels along axis a, truncated at 3 sigma and
// renormalised, edges clamped) of `in` (dims n) into `out` (not `in`); `tmp` is scratch. Along y
// and z whole rows and planes are combined, so every inner loop runs over contiguous memory.
void blur(const std::vector<float>& in, std::vector<float>& out, std::vector<float>& tmp, const std::array<int64_t, 3>& n,
          const std::array<double, 3>& sigma_vox, int threads) {
  std::array<std::vector<float>, 3> kernels;
  std::array<int, 3> radius{};
  for (int a = 0; a < 3; ++a) {
    const int r = radius[static_cast<std::size_t>(a)] = static_cast<int>(std::ceil(3.0 * sigma_vox[static_cast<std::size_t>(a)]));
    std::vector<double> k(static_cast<std::size_t>(2 * r + 1));
    double sum = 0.0;
    for (int q = -r; q <= r; ++q)
      sum += k[static_cast<std::size_t>(q + r)] =
          std::exp(-0.5 * q * q / (sigma_vox[static_cast<std::size_t>(a)] * sigma_vox[static_cast<std::size_t>(a)]));
    for (const double v : k) kernels[static_cast<std::size_t>(a)].push_back(static_cast<float>(v / sum));
  }
  const int64_t nx = n[0], ny = n[1], nz = n[2];
  // x: in -> tmp, one row at a time (clamped reads only near the row's ends).
  {
    const int r = radius[0];
    const float* k = kernels[0].data();
#pragma omp parallel for schedule(static) num_threads(threads)
    for (int64_t row = 0; row < ny * nz; ++row) {
      const float* s = in.data() + row * nx;
      float* d = tmp.data() + row * nx;
      for (int64_t i = 0; i < nx; ++i) {
        float acc = 0.0f;
        if (i >= r && i + r < nx) {
          for (int q = -r; q <= r; ++q) acc += k[q + r] * s[i + q];
        } else {
          for (int q = -r; q <= r; ++q) acc += k[q + r] * s[std::clamp<int64_t>(i + q, 0, nx - 1)];
        }
        d[i] = acc;
      }
    }
  }
  // y: tmp -> out, rows combined within each z plane.
  {
    const int r = radius[1];
    const float* k = kernels[1].data();
#pragma omp parallel for schedule(static) num_threads(threads)
    for (int64_t z = 0; z < nz; ++z)
      for (int64_t j = 0; j < ny; ++j) {
        float* d = out.data() + (z * ny + j) * nx;
        std::fill(d, d + nx, 0.0f);
        for (int q = -r; q <= r; ++q) {
          const float* s = tmp.data() + (z * ny + std::clamp<int64_t>(j + q, 0, ny - 1)) * nx;
          const float w = k[q + r];
          for (int64_t i = 0; i < nx; ++i) d[i] += w * s[i];
        }
      }
  }
  // z: out -> tmp, planes combined; then swapped into out.
  {
    const int r = radius[2];
    const float* k = kernels[2].data();
    const int64_t plane = nx * ny;
#pragma omp parallel for schedule(static) num_threads(threads)
    for (int64_t z = 0; z < nz; ++z) {
      float* d = tmp.data() + z * plane;
      std::fill(d, d + plane, 0.0f);
      for (int q = -r; q <= r; ++q) {
        const float* s = out.data() + std::clamp<int64_t>(z + q, 0, nz - 1) * plane;
        const float w = k[q + r];
        for (int64_t i = 0; i < plane; ++i) d[i] += w * s[i];
      }
    }
  }
  out.swap(tmp);
}

// One projection (see the header, step 2): f = base + K (side * lambda), K the Gaussian of
// sigma_vox voxels, lambda >= 0 from projected dual ascent with FISTA momentum and gradient restart,
// for at most `iterations` or until no voxel is more than `tolerance` mm on its wrong side.
// Returns the iterations run; `violation` the largest remaining violation in mm.
int project_on_constraints(const std::vector<float>& base, const std::vector<int8_t>& side, const std::array<int64_t, 3>& n,
                           const std::array<double, 3>& sigma_vox, double margin_mm, int iterations, double tolerance,
                           int threads, std::vector<float>& f, double& violation) {
  const int64_t total = n[0] * n[1] * n[2];
  const int64_t blocks = (total + kSumBlock - 1) / kSumBlock;
  std::vector<float> lambda(static_cast<std::size_t>(total), 0.0f);
  std::vector<float> lambda_prev = lambda, ext = lambda, load = lambda, corr = lambda, tmp = lambda;
  std::vector<double> block_dot(static_cast<std::size_t>(blocks)), block_viol(static_cast<std::size_t>(blocks));
  f = base;
  violation = 0.0;
  for (int64_t w = 0; w < total; ++w)
    violation = std::max(violation, margin_mm - side[static_cast<std::size_t>(w)] * double(base[static_cast<std::size_t>(w)]));
  double t = 1.0;
  int it = 0;
  for (; it < iterations && violation > tolerance; ++it) {
#pragma omp parallel for schedule(static) num_threads(threads)
    for (int64_t w = 0; w < total; ++w)
      load[static_cast<std::size_t>(w)] = side[static_cast<std::size_t>(w)] * ext[static_cast<std::size_t>(w)];
    blur(load, corr, tmp, n, sigma_vox, threads);
#pragma omp parallel for schedule(static) num_threads(threads)
    for (int64_t b = 0; b < blocks; ++b) {
      double dot = 0.0, viol = 0.0;
      for (int64_t w = b * kSumBlock; w < std::min(total, (b + 1) * kSumBlock); ++w) {
        const std::size_t i = static_cast<std::size_t>(w);
        const double fi = double(base[i]) + corr[i];
        const double gap = margin_mm - side[i] * fi;  // > 0: on the wrong side
        viol = std::max(viol, gap);
        const double next = std::max(0.0, ext[i] + gap);
        dot += (ext[i] - next) * (next - lambda[i]);
        lambda_prev[i] = lambda[i];
        lambda[i] = static_cast<float>(next);
        f[i] = static_cast<float>(fi);
      }
      block_dot[static_cast<std::size_t>(b)] = dot;
      block_viol[static_cast<std::size_t>(b)] = viol;
    }
    double dot = 0.0;
    violation = 0.0;
    for (int64_t b = 0; b < blocks; ++b)
      dot += block_dot[static_cast<std::size_t>(b)], violation = std::max(violation, block_viol[static_cast<std::size_t>(b)]);
    // Momentum, restarted when it points the wrong way (O'Donoghue & Candes 2015, gradient scheme).
    double beta = 0.0;
    if (dot > 0.0) {
      t = 1.0;
    } else {
      const double t_next = 0.5 * (1.0 + std::sqrt(1.0 + 4.0 * t * t));
      beta = (t - 1.0) / t_next;
      t = t_next;
    }
#pragma omp parallel for schedule(static) num_threads(threads)
    for (int64_t w = 0; w < total; ++w) {
      const std::size_t i = static_cast<std::size_t>(w);
      ext[i] = static_cast<float>(std::max(0.0, lambda[i] + beta * (double(lambda[i]) - lambda_prev[i])));
    }
  }
  violation = std::max(violation, 0.0);
  return it;
}

// The tissue's bounding box on a lattice of dims n (lo > hi when there is none).
template <class Inside>
void bounding_box(const std::array<int64_t, 3>& n, Inside inside, std::array<int64_t, 3>& lo, std::array<int64_t, 3>& hi,
                  int64_t& count) {
  lo = n, hi = {-1, -1, -1}, count = 0;
  for (int64_t k = 0; k < n[2]; ++k)
    for (int64_t j = 0; j < n[1]; ++j)
      for (int64_t i = 0; i < n[0]; ++i)
        if (inside(i, j, k)) {
          ++count;
          const int64_t idx[3] = {i, j, k};
          for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], idx[a]), hi[a] = std::max(hi[a], idx[a]);
        }
}

}  // namespace

MaskBlocks mask_blocks(const Volume<uint16_t>& labels, int max_factor) {
  MaskBlocks blocks;
  const auto& n = labels.geometry.dims;
  const int64_t stride[3] = {1, n[0], n[0] * n[1]};
  for (int a = 0; a < 3; ++a) {
    // Positions p where slice p and slice p + 1 along axis a differ somewhere.
    std::vector<int64_t> changes;
    for (int64_t p = 0; p + 1 < n[a]; ++p) {
      bool differs = false;
      const int b = (a + 1) % 3, c = (a + 2) % 3;
      for (int64_t v = 0; v < n[c] && !differs; ++v)
        for (int64_t u = 0; u < n[b] && !differs; ++u) {
          const int64_t at = p * stride[a] + u * stride[b] + v * stride[c];
          differs = (labels.voxels[static_cast<std::size_t>(at)] != 0) !=
                    (labels.voxels[static_cast<std::size_t>(at + stride[a])] != 0);
        }
      if (differs) changes.push_back(p);
    }
    // Too few changes to tell a block from an object's own size (a box of 4 voxels is not a
    // segmentation at 4 voxels).
    if (changes.size() < static_cast<std::size_t>(kMinBlockChanges)) continue;
    int64_t g = 0;
    for (std::size_t c = 1; c < changes.size(); ++c) g = std::gcd(g, changes[c] - changes[c - 1]);
    if (g < 2 || g > max_factor) continue;
    blocks.factor[static_cast<std::size_t>(a)] = static_cast<int>(g);
    blocks.offset[static_cast<std::size_t>(a)] = static_cast<int>((changes[0] + 1) % g);
  }
  return blocks;
}

Volume<float> anti_aliased_mask(const Volume<uint16_t>& labels, const AntiAliasOptions& options, AntiAliasStats* stats) {
  const ImageGeometry& geo = labels.geometry;
  AntiAliasStats local_stats;
  AntiAliasStats& st = stats ? *stats : local_stats;
  st = {};
  if (!(options.correction_sigma_voxels > 0.0) || !std::isfinite(options.correction_sigma_voxels) || options.max_iterations < 0 ||
      !(options.margin >= 0.0) || !(options.margin < 0.5) || !(options.tolerance > 0.0))
    throw InputError("anti-aliasing", "options", "need correction sigma > 0, iterations >= 0, 0 <= margin < 0.5, tolerance > 0");
  st.blocks = options.detect_blocks ? mask_blocks(labels) : MaskBlocks{};
  const std::array<int, 3> k = st.blocks.factor, o = st.blocks.offset;

  // The mask's own lattice: one voxel per block (blocks cut by the lattice's edge included).
  std::array<int64_t, 3> nn{};
  for (int a = 0; a < 3; ++a) nn[a] = (o[a] > 0 ? 1 : 0) + (geo.dims[a] - o[a] + k[a] - 1) / k[a];
  // Fine index of native voxel c's centre: o + (c - [o > 0]) k + (k - 1) / 2.
  const auto fine_of = [&](int a, double c) { return o[a] + (c - (o[a] > 0 ? 1 : 0)) * k[a] + 0.5 * (k[a] - 1); };
  const auto native_label = [&](int64_t i, int64_t j, int64_t l) {
    const int64_t c[3] = {i, j, l};
    int64_t f[3];
    for (int a = 0; a < 3; ++a)
      f[a] = std::clamp<int64_t>(std::llround(std::floor(fine_of(a, double(c[a])))), 0, geo.dims[a] - 1);
    return labels(f[0], f[1], f[2]) != 0;
  };
  Eigen::Vector3d h3;
  for (int a = 0; a < 3; ++a) h3[a] = geo.spacing[a] * k[a];
  const double h = h3.minCoeff();
  const double sigma = options.sigma_mm < 0.0 ? kDefaultSigmaVoxels * h3.maxCoeff() : options.sigma_mm;
  if (!std::isfinite(sigma) || sigma <= 0.0)
    throw InputError("--sigma-mm", "", "must be a finite number > 0 for the anti-aliased field");
  double extent = 0.0;
  for (int a = 0; a < 3; ++a)
    extent = std::max(extent, geo.spacing[a] * static_cast<double>(geo.dims[static_cast<std::size_t>(a)]));
  if (sigma > extent) {
    throw InputError("--sigma-mm", "",
                     std::to_string(sigma) + " mm is wider than the whole mask (" + std::to_string(extent) +
                         " mm): it would smooth it flat; use at most that");
  }
  const double scale = std::sqrt(2.0 * std::numbers::pi) * sigma;  // the smoothed indicator's slope at a plane is 1/scale
  const auto far_outside = static_cast<float>(-0.5 * scale);
  const int threads = options.threads > 0 ? options.threads : omp_get_max_threads();

  std::array<int64_t, 3> bb_lo{}, bb_hi{};
  int64_t inside_count = 0;
  bounding_box(nn, native_label, bb_lo, bb_hi, inside_count);
  if (inside_count == 0) return Volume<float>(geo, far_outside);
  if (inside_count == nn[0] * nn[1] * nn[2]) return Volume<float>(geo, -far_outside);

  // The working box on the native lattice: the tissue plus room for g to reach its far value.
  std::array<int64_t, 3> lo{}, n{};
  std::array<double, 3> sigma_vox{};
  for (int a = 0; a < 3; ++a) {
    sigma_vox[a] = sigma / h3[a];
    const int64_t margin = static_cast<int64_t>(std::ceil(3.0 * sigma_vox[a])) + 2;
    lo[a] = std::max<int64_t>(bb_lo[a] - margin, 0);
    n[a] = std::min<int64_t>(bb_hi[a] + margin, nn[a] - 1) - lo[a] + 1;
  }
  const int64_t total = n[0] * n[1] * n[2];
  const int64_t stride[3] = {1, n[0], n[0] * n[1]};
  std::vector<int8_t> side(static_cast<std::size_t>(total));
  std::vector<float> indicator(static_cast<std::size_t>(total)), g(static_cast<std::size_t>(total)),
      tmp(static_cast<std::size_t>(total));
  for (int64_t l = 0; l < n[2]; ++l)
    for (int64_t j = 0; j < n[1]; ++j)
      for (int64_t i = 0; i < n[0]; ++i) {
        const std::size_t w = static_cast<std::size_t>(i + stride[1] * j + stride[2] * l);
        side[w] = native_label(lo[0] + i, lo[1] + j, lo[2] + l) ? 1 : -1;
        indicator[w] = side[w] > 0 ? 1.0f : 0.0f;
      }
  blur(indicator, g, tmp, n, sigma_vox, threads);
  for (float& v : g) v = static_cast<float>((v - 0.5) * scale);

  const double margin_mm = options.margin * h;
  std::vector<float> f = g;
  double violation = 0.0;
  for (int64_t w = 0; w < total; ++w)
    violation = std::max(violation, margin_mm - side[static_cast<std::size_t>(w)] * double(g[static_cast<std::size_t>(w)]));
  st.start_violation_mm = st.last_violation_mm = std::max(violation, 0.0);
  const double widths[3] = {options.correction_sigma_voxels, 0.5 * options.correction_sigma_voxels,
                            0.25 * options.correction_sigma_voxels};
  for (int stage = 0; stage < 3; ++stage) {
    const double width = std::max(widths[stage], kNarrowestCorrection);
    std::array<double, 3> vox{};
    for (int a = 0; a < 3; ++a) vox[a] = width * h / h3[a];
    const std::vector<float> base = f;
    const bool last = stage == 2 || width == kNarrowestCorrection;
    st.iterations +=
        project_on_constraints(base, side, n, vox, margin_mm, last ? options.max_iterations : options.stage_iterations,
                               options.tolerance * h, threads, f, st.last_violation_mm);
    if (last) break;
  }
  // The last small violations (at most tolerance x h): clamped, so the constraint holds exactly at
  // every native voxel.
  for (int64_t w = 0; w < total; ++w) {
    const std::size_t i = static_cast<std::size_t>(w);
    if (side[i] > 0 && f[i] < static_cast<float>(margin_mm)) f[i] = static_cast<float>(margin_mm), ++st.clamped_voxels;
    if (side[i] < 0 && f[i] > static_cast<float>(-margin_mm)) f[i] = static_cast<float>(-margin_mm), ++st.clamped_voxels;
  }

  // Back to the mask's lattice (trilinear from the native one; the same lattice when no blocks).
  Volume<float> out(geo, far_outside);
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int64_t l = 0; l < geo.dims[2]; ++l)
    for (int64_t j = 0; j < geo.dims[1]; ++j)
      for (int64_t i = 0; i < geo.dims[0]; ++i) {
        const int64_t idx[3] = {i, j, l};
        int64_t c0[3];
        double tt[3];
        bool outside_box = false;
        for (int a = 0; a < 3; ++a) {
          // Native continuous index of this fine voxel, relative to the box.
          const double c = (double(idx[a]) - o[a] - 0.5 * (k[a] - 1)) / k[a] + (o[a] > 0 ? 1 : 0) - double(lo[a]);
          const double cc = std::clamp(c, 0.0, double(n[a] - 1));
          outside_box = outside_box || c < -1.0 || c > double(n[a]);
          c0[a] = std::min<int64_t>(static_cast<int64_t>(std::floor(cc)), std::max<int64_t>(n[a] - 2, 0));
          tt[a] = n[a] > 1 ? cc - double(c0[a]) : 0.0;
        }
        if (outside_box) continue;
        double v = 0.0;
        for (int corner = 0; corner < 8; ++corner) {
          double wgt = 1.0;
          int64_t at = 0;
          for (int a = 0; a < 3; ++a) {
            const int bit = (corner >> a) & 1;
            wgt *= bit ? tt[a] : 1.0 - tt[a];
            at += std::min<int64_t>(c0[a] + bit, n[a] - 1) * stride[a];
          }
          if (wgt != 0.0) v += wgt * f[static_cast<std::size_t>(at)];
        }
        out(i, j, l) = static_cast<float>(v);
      }
  return out;
}

}  // namespace ctsurg
