#include "ctsurg/preprocess/label_resampling.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace ctsurg {

LabelResampling resample_labels_nearest(const Volume<uint16_t>& source, const ImageGeometry& target) {
  LabelResampling out;
  out.labels = Volume<uint16_t>(target);
  const ImageGeometry& s = source.geometry;
  // Target index -> source index is affine: A * ijk + b.
  const Eigen::Matrix3d to_source = s.index_to_world_matrix().inverse();
  const Eigen::Matrix3d a = to_source * target.index_to_world_matrix();
  const Eigen::Vector3d b = to_source * (target.origin - s.origin);
  const Eigen::Matrix3d m = s.index_to_world_matrix();
  double max_offset = 0.0;
  int64_t outside = 0;
#pragma omp parallel for reduction(max : max_offset) reduction(+ : outside) schedule(static)
  for (int64_t k = 0; k < target.dims[2]; ++k) {
    for (int64_t j = 0; j < target.dims[1]; ++j) {
      for (int64_t i = 0; i < target.dims[0]; ++i) {
        const Eigen::Vector3d p = a * Eigen::Vector3d(double(i), double(j), double(k)) + b;
        const Eigen::Vector3d r = p.array().round();
        if (r[0] < 0 || r[1] < 0 || r[2] < 0 || r[0] >= s.dims[0] || r[1] >= s.dims[1] || r[2] >= s.dims[2]) {
          ++outside;
          continue;
        }
        max_offset = std::max(max_offset, (m * (p - r)).norm());
        out.labels(i, j, k) = source(int64_t(r[0]), int64_t(r[1]), int64_t(r[2]));
      }
    }
  }
  out.max_offset_mm = max_offset;
  out.outside = outside;
  return out;
}

}  // namespace ctsurg
