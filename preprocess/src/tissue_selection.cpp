#include "ctsurg/preprocess/tissue_selection.h"

#include "ctsurg/core/error.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace ctsurg {

namespace {

std::pair<float, float> value_range(const Volume<float>& v) {
  if (v.voxels.empty()) throw RuntimeError("tissue selection: empty volume");
  const auto [lo, hi] = std::minmax_element(v.voxels.begin(), v.voxels.end());
  return {*lo, *hi};
}

std::string format_window(double lo, double hi) {
  std::ostringstream s;
  s << "[" << lo << ", " << hi << "] HU";
  return s.str();
}

}  // namespace

Volume<uint16_t> select_hu_window(const Volume<float>& hu, double hu_min, double hu_max, const std::string& file,
                                  uint16_t label) {
  const auto [lo, hi] = value_range(hu);
  if (!(hu_min <= hu_max)) {
    throw InputError(file, "--hu-min/--hu-max", "empty window " + format_window(hu_min, hu_max) + " (min > max)");
  }
  Volume<uint16_t> mask(hu.geometry, 0);
  int64_t selected = 0;
  for (size_t n = 0; n < hu.voxels.size(); ++n) {
    const double v = hu.voxels[n];
    if (v >= hu_min && v <= hu_max) {
      mask.voxels[n] = label;
      ++selected;
    }
  }
  if (selected == 0) {
    throw InputError(file, "--hu-min/--hu-max",
                     "no voxel inside the window " + format_window(hu_min, hu_max) + "; the volume spans " +
                         format_window(lo, hi));
  }
  return mask;
}

double otsu_threshold(const Volume<float>& hu, const std::string& file, int bins) {
  const auto [lo, hi] = value_range(hu);
  if (!(hi > lo)) {
    std::ostringstream s;
    s << "the volume is constant (" << lo << " HU everywhere); Otsu needs two intensity classes";
    throw InputError(file, "--otsu", s.str());
  }
  bins = std::max(bins, 2);
  const double width = (double(hi) - double(lo)) / bins;
  std::vector<double> hist(static_cast<size_t>(bins), 0.0);
  for (const float v : hu.voxels) {
    const int b = std::min(bins - 1, static_cast<int>((double(v) - lo) / width));
    hist[static_cast<size_t>(b)] += 1.0;
  }
  // Bin centres as class values; w0/mu0 accumulate the classes below and at bin t.
  double total = 0.0, sum_all = 0.0;
  for (int b = 0; b < bins; ++b) {
    total += hist[size_t(b)];
    sum_all += hist[size_t(b)] * (b + 0.5);
  }
  double w0 = 0.0, sum0 = 0.0, best = -1.0;
  int best_bin = 0;
  for (int t = 0; t < bins - 1; ++t) {
    w0 += hist[size_t(t)];
    sum0 += hist[size_t(t)] * (t + 0.5);
    const double w1 = total - w0;
    if (w0 <= 0.0 || w1 <= 0.0) continue;
    const double mu0 = sum0 / w0, mu1 = (sum_all - sum0) / w1;
    const double between = w0 * w1 * (mu0 - mu1) * (mu0 - mu1);
    if (between > best) {
      best = between;
      best_bin = t;
    }
  }
  return lo + width * (best_bin + 1);
}

Volume<uint16_t> select_otsu(const Volume<float>& hu, const std::string& file, uint16_t label) {
  const double t = otsu_threshold(hu, file);
  Volume<uint16_t> mask(hu.geometry, 0);
  for (size_t n = 0; n < hu.voxels.size(); ++n) mask.voxels[n] = hu.voxels[n] > t ? label : 0;
  return mask;
}

Volume<uint16_t> select_labels(const Volume<float>& labels, const std::vector<uint16_t>& ids, const std::string& file) {
  Volume<uint16_t> all(labels.geometry, 0);
  for (size_t n = 0; n < labels.voxels.size(); ++n) {
    const float v = labels.voxels[n];
    if (!(v >= 0.0f && v <= 65535.0f) || std::floor(v) != v) {
      const auto nx = labels.geometry.dims[0], ny = labels.geometry.dims[1];
      const auto idx = static_cast<int64_t>(n);
      std::ostringstream s;
      s << "label volume values must be integers in [0, 65535]; voxel (" << idx % nx << ", " << (idx / nx) % ny << ", "
        << idx / (nx * ny) << ") holds " << v;
      throw InputError(file, "labels", s.str());
    }
    all.voxels[n] = static_cast<uint16_t>(v);
  }
  if (ids.empty()) {
    if (count_tissue_voxels(all) == 0) throw InputError(file, "labels", "the label volume holds no non-zero label");
    return all;
  }
  Volume<uint16_t> mask(labels.geometry, 0);
  int64_t selected = 0;
  for (size_t n = 0; n < all.voxels.size(); ++n) {
    const uint16_t v = all.voxels[n];
    if (v != 0 && std::find(ids.begin(), ids.end(), v) != ids.end()) {
      mask.voxels[n] = v;
      ++selected;
    }
  }
  if (selected == 0) {
    std::ostringstream s;
    s << "none of the labels";
    for (const auto id : ids) s << " " << id;
    s << " occurs in the volume; it holds";
    const auto present = labels_present(all);
    if (present.empty()) s << " no label";
    for (size_t n = 0; n < present.size() && n < 40; ++n) s << " " << present[n];
    if (present.size() > 40) s << " ...";
    throw InputError(file, "--labels", s.str());
  }
  return mask;
}

std::vector<uint16_t> labels_present(const Volume<uint16_t>& mask) {
  std::vector<char> seen(65536, 0);
  for (const auto v : mask.voxels) seen[v] = 1;
  std::vector<uint16_t> out;
  for (int v = 1; v < 65536; ++v)
    if (seen[size_t(v)]) out.push_back(static_cast<uint16_t>(v));
  return out;
}

int64_t count_tissue_voxels(const Volume<uint16_t>& mask) {
  return static_cast<int64_t>(mask.voxels.size()) - std::count(mask.voxels.begin(), mask.voxels.end(), uint16_t{0});
}

}  // namespace ctsurg
