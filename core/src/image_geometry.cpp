#include "ctsurg/core/image_geometry.h"

#include "ctsurg/core/error.h"

#include <Eigen/LU>
#include <cmath>
#include <sstream>

namespace ctsurg {

Eigen::Matrix3d ImageGeometry::index_to_world_matrix() const { return direction * spacing.asDiagonal(); }

Eigen::Vector3d ImageGeometry::index_to_world(const Eigen::Vector3d& ijk) const {
  return origin + index_to_world_matrix() * ijk;
}

Eigen::Vector3d ImageGeometry::world_to_index(const Eigen::Vector3d& xyz) const {
  return index_to_world_matrix().inverse() * (xyz - origin);
}

double ImageGeometry::voxel_volume_mm3() const { return std::abs(index_to_world_matrix().determinant()); }

bool ImageGeometry::is_orthonormal(double tolerance) const {
  return (direction.transpose() * direction - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <= tolerance;
}

bool ImageGeometry::same_lattice(const ImageGeometry& other, double tolerance_mm) const {
  if (dims != other.dims) return false;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d ijk((c & 1) ? double(dims[0] - 1) : 0.0, (c & 2) ? double(dims[1] - 1) : 0.0,
                              (c & 4) ? double(dims[2] - 1) : 0.0);
    if ((index_to_world(ijk) - other.index_to_world(ijk)).norm() > tolerance_mm) return false;
  }
  return true;
}

void ImageGeometry::validate(const std::string& file) const {
  int64_t count = 1;
  for (int a = 0; a < 3; ++a) {
    if (dims[a] <= 0) {
      throw InputError(file, "dims", "dimension " + std::to_string(a) + " must be positive, got " + std::to_string(dims[a]));
    }
    if (__builtin_mul_overflow(count, dims[a], &count) || count > kMaxVoxels) {
      throw InputError(file, "dims",
                       std::to_string(dims[0]) + " x " + std::to_string(dims[1]) + " x " + std::to_string(dims[2]) +
                           " voxels: more than 2^48, not an image");
    }
    if (!std::isfinite(spacing[a]) || spacing[a] <= 0.0) {
      std::ostringstream s;
      s << "spacing along axis " << a << " must be a positive number of mm, got " << spacing[a];
      throw InputError(file, "spacing", s.str());
    }
    if (spacing[a] < kMinSpacingMm || spacing[a] > kMaxSpacingMm) {
      std::ostringstream s;
      s << "spacing along axis " << a << " is " << spacing[a] << " mm, outside [" << kMinSpacingMm << ", "
        << kMaxSpacingMm << "] mm (corrupt header?)";
      throw InputError(file, "spacing", s.str());
    }
    if (!std::isfinite(origin[a])) throw InputError(file, "origin", "origin is not finite");
    if (std::abs(origin[a]) > kMaxCoordinateMm || spacing[a] * static_cast<double>(dims[a]) > kMaxCoordinateMm) {
      std::ostringstream s;
      s << "the lattice reaches " << std::abs(origin[a]) + spacing[a] * static_cast<double>(dims[a])
        << " mm from the scanner's origin along axis " << a << ", more than " << kMaxCoordinateMm << " mm (corrupt header?)";
      throw InputError(file, "origin", s.str());
    }
    const double len = direction.col(a).norm();
    if (!direction.col(a).allFinite() || std::abs(len - 1.0) > 1e-3) {
      std::ostringstream s;
      s << "column " << a << " of the direction matrix must be a unit vector, has length " << len;
      throw InputError(file, "direction", s.str());
    }
  }
  if (std::abs(direction.determinant()) < 1e-3) {
    throw InputError(file, "direction", "direction matrix is singular (index axes are parallel)");
  }
}

}  // namespace ctsurg
