#include "ctsurg/preprocess/slice_stack.h"

#include "ctsurg/core/error.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

namespace ctsurg {

ImageGeometry SliceStack::geometry(int columns, int rows, double column_spacing_mm, double row_spacing_mm,
                                   const Eigen::Vector3d& first_position) const {
  ImageGeometry g;
  g.dims = {columns, rows, static_cast<int64_t>(order.size())};
  g.spacing = Eigen::Vector3d(column_spacing_mm, row_spacing_mm, mean_step_mm);
  g.origin = first_position;
  g.direction.col(0) = row_dir;
  g.direction.col(1) = col_dir;
  g.direction.col(2) = step_direction;
  return g;
}

SliceStack analyse_slice_stack(const Eigen::Vector3d& row_dir, const Eigen::Vector3d& col_dir,
                               const std::vector<Eigen::Vector3d>& positions, const std::string& source,
                               double tolerance_mm) {
  const std::size_t n = positions.size();
  if (n < 2) {
    throw InputError(source, "ImagePositionPatient",
                     "a volume needs at least two slices, found " + std::to_string(n));
  }
  const Eigen::Vector3d normal = row_dir.cross(col_dir).normalized();
  SliceStack s;
  s.row_dir = row_dir;
  s.col_dir = col_dir;
  s.order.resize(n);
  std::iota(s.order.begin(), s.order.end(), 0);
  std::stable_sort(s.order.begin(), s.order.end(),
                   [&](int a, int b) { return normal.dot(positions[a]) < normal.dot(positions[b]); });
  const Eigen::Vector3d first = positions[s.order.front()], last = positions[s.order.back()];
  const double extent = (last - first).norm();
  if (extent <= 1e-6) throw InputError(source, "ImagePositionPatient", "all slices are at the same position");
  s.step_direction = (last - first) / extent;
  s.mean_step_mm = extent / double(n - 1);
  s.offsets_mm.resize(n);
  s.min_gap_mm = std::numeric_limits<double>::infinity();
  s.max_gap_mm = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Vector3d d = positions[s.order[k]] - first;
    s.offsets_mm[k] = d.dot(s.step_direction);
    s.max_off_line_mm = std::max(s.max_off_line_mm, (d - s.offsets_mm[k] * s.step_direction).norm());
    if (k > 0) {
      const double gap = s.offsets_mm[k] - s.offsets_mm[k - 1];
      if (gap <= 1e-3) {
        std::ostringstream m;
        m << "two slices at the same position (" << first.x() + d.x() << ", " << first.y() + d.y() << ", "
          << first.z() + d.z() << ") mm: duplicate images or several acquisitions in one series";
        throw InputError(source, "ImagePositionPatient", m.str());
      }
      s.min_gap_mm = std::min(s.min_gap_mm, gap);
      s.max_gap_mm = std::max(s.max_gap_mm, gap);
    }
  }
  if (s.max_off_line_mm > 0.5 + 0.01 * extent) {
    std::ostringstream m;
    m << "slice positions do not lie on a line (a slice is " << s.max_off_line_mm
      << " mm off): not one volume";
    throw InputError(source, "ImagePositionPatient", m.str());
  }
  const double cos_tilt = std::clamp(std::abs(s.step_direction.dot(normal)), 0.0, 1.0);
  s.tilt_deg = std::acos(cos_tilt) * 180.0 / M_PI;
  const double tol = tolerance_mm > 0 ? tolerance_mm : std::max(0.01, 0.01 * s.mean_step_mm);
  s.uneven = (s.max_gap_mm - s.mean_step_mm > tol) || (s.mean_step_mm - s.min_gap_mm > tol);
  if (s.uneven) {
    for (std::size_t k = 1; k < n; ++k) {
      const double ratio = (s.offsets_mm[k] - s.offsets_mm[k - 1]) / s.min_gap_mm;
      const double whole = std::round(ratio);
      if (whole >= 2.0 && std::abs(ratio - whole) < 0.05) s.missing_slices += static_cast<int>(whole) - 1;
    }
  }
  return s;
}

Volume<float> resample_even_slices(const Volume<float>& slices, const SliceStack& stack) {
  const auto& g = slices.geometry;
  const int64_t n = g.dims[2];
  const double extent = stack.offsets_mm.back();
  const int64_t m = static_cast<int64_t>(std::ceil(extent / stack.min_gap_mm - 1e-9)) + 1;
  ImageGeometry out_geo = g;
  out_geo.dims[2] = m;
  out_geo.spacing[2] = extent / double(m - 1);
  Volume<float> out(out_geo);
  const int64_t plane = g.dims[0] * g.dims[1];
  int64_t lower = 0;
  for (int64_t k = 0; k < m; ++k) {
    const double z = std::min(extent, double(k) * out_geo.spacing[2]);
    while (lower + 2 < n && stack.offsets_mm[static_cast<std::size_t>(lower + 1)] <= z) ++lower;
    const double z0 = stack.offsets_mm[static_cast<std::size_t>(lower)];
    const double z1 = stack.offsets_mm[static_cast<std::size_t>(lower + 1)];
    const float w = static_cast<float>(std::clamp((z - z0) / (z1 - z0), 0.0, 1.0));
    const float* a = slices.voxels.data() + lower * plane;
    const float* b = a + plane;
    float* o = out.voxels.data() + k * plane;
    for (int64_t p = 0; p < plane; ++p) o[p] = a[p] + w * (b[p] - a[p]);
  }
  return out;
}

}  // namespace ctsurg
