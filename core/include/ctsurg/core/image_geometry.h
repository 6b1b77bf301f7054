// The geometry of a voxel lattice in patient space.
//
// Conventions (used by every ctsurg stage and file):
//  - World coordinates are DICOM patient coordinates, LPS (x to the patient's Left, y to Posterior,
//    z to Superior), in millimetres.
//  - Index (i, j, k) addresses voxel centres; i varies fastest in memory (x fastest), so the flat
//    index is i + dims[0] * (j + dims[1] * k).
//  - world = origin + direction * diag(spacing) * (i, j, k)^T. Column c of `direction` is the unit
//    world direction of index axis c. It is usually orthonormal; a gantry-tilted CT series gives a
//    sheared (non-orthogonal) matrix, which is kept so that every voxel sits where it was scanned.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>

namespace ctsurg {

struct ImageGeometry {
  std::array<int64_t, 3> dims{0, 0, 0};             // voxels along i, j, k
  Eigen::Vector3d spacing{1.0, 1.0, 1.0};           // mm between voxel centres along i, j, k
  Eigen::Vector3d origin{0.0, 0.0, 0.0};            // LPS mm of the centre of voxel (0, 0, 0)
  Eigen::Matrix3d direction = Eigen::Matrix3d::Identity();  // unit columns, LPS

  int64_t voxel_count() const { return dims[0] * dims[1] * dims[2]; }
  int64_t flat_index(int64_t i, int64_t j, int64_t k) const { return i + dims[0] * (j + dims[1] * k); }

  // 3x3 matrix taking index offsets to LPS mm offsets: direction * diag(spacing).
  Eigen::Matrix3d index_to_world_matrix() const;
  // LPS mm of a (possibly fractional) index.
  Eigen::Vector3d index_to_world(const Eigen::Vector3d& ijk) const;
  // Fractional index of an LPS mm point.
  Eigen::Vector3d world_to_index(const Eigen::Vector3d& xyz) const;
  // Volume of one voxel in mm^3 (|det| of index_to_world_matrix, correct for sheared lattices).
  double voxel_volume_mm3() const;
  // True when the direction columns are orthonormal within `tolerance`.
  bool is_orthonormal(double tolerance = 1e-6) const;
  // True when both lattices have the same dims and their voxel centres agree within `tolerance_mm`
  // (checked at the eight corner voxels).
  bool same_lattice(const ImageGeometry& other, double tolerance_mm = 1e-3) const;

  // Throws InputError(file, field, problem) unless the geometry is finite and sane: dims positive
  // with at most kMaxVoxels voxels (so voxel_count() cannot overflow), spacing in [kMinSpacingMm,
  // kMaxSpacingMm], origin and extent within kMaxCoordinateMm of the scanner's origin, and
  // direction with finite unit columns, not singular. A corrupt header (a spacing of 1e38 mm) is
  // refused here instead of hanging a later stage.
  void validate(const std::string& file) const;

  static constexpr int64_t kMaxVoxels = int64_t{1} << 48;
  static constexpr double kMinSpacingMm = 1e-4;        // 0.1 um: beyond micro-CT
  static constexpr double kMaxSpacingMm = 1e4;         // 10 m
  static constexpr double kMaxCoordinateMm = 1e7;      // 10 km
};

}  // namespace ctsurg
