// Geometry of a stack of 2D CT slices (a DICOM series), from ImagePositionPatient and
// ImageOrientationPatient alone, and the resampling of unevenly spaced stacks.
//
// DICOM PS3.3 C.7.6.2.1.1: ImageOrientationPatient gives the row direction (increasing column
// index) and the column direction (increasing row index); slices are ordered by the projection of
// ImagePositionPatient on the slice normal row x col. The slice step is the distance between
// consecutive positions, never SliceThickness. With gantry tilt the positions move along a line that
// is not the slice normal: the lattice is sheared, and the tilt is the angle between that line and
// the normal.
#pragma once

#include "ctsurg/core/image_geometry.h"
#include "ctsurg/core/volume.h"

#include <Eigen/Core>
#include <string>
#include <vector>

namespace ctsurg {

struct SliceStack {
  Eigen::Vector3d row_dir, col_dir;  // ImageOrientationPatient (unit, LPS)
  std::vector<int> order;            // slice indices sorted along the normal
  std::vector<double> offsets_mm;    // position of each sorted slice along `step_direction`, first = 0
  Eigen::Vector3d step_direction;    // unit vector from the first to the last slice position (LPS)
  double mean_step_mm = 0.0;         // (last - first) / (n - 1)
  double min_gap_mm = 0.0, max_gap_mm = 0.0;
  double tilt_deg = 0.0;             // angle between step_direction and the slice normal
  double max_off_line_mm = 0.0;      // largest distance of a position from the first-last line
  bool uneven = false;               // some gap differs from the mean step by more than the tolerance
  int missing_slices = 0;            // gaps that are whole multiples (>= 2) of the smallest gap, as slices

  // Lattice with in-plane axes from the orientation, slice axis along step_direction with the mean
  // step: exact for every slice when the stack is even; for an uneven stack exact for the first and
  // the last slice only (what dcm2niix writes).
  ImageGeometry geometry(int columns, int rows, double column_spacing_mm, double row_spacing_mm,
                         const Eigen::Vector3d& first_position) const;
};

// Sorts and measures the stack. `row_dir` and `col_dir` are the two ImageOrientationPatient
// vectors (unit, LPS); `positions` are the ImagePositionPatient of each slice (LPS mm).
// Throws InputError(source, "ImagePositionPatient", ...) for fewer than two slices, two slices at
// the same position, or positions that do not lie on a line (off by more than 0.5 mm + 1%).
// `tolerance_mm` decides `uneven` (default: 1% of the mean step, at least 0.01 mm).
SliceStack analyse_slice_stack(const Eigen::Vector3d& row_dir, const Eigen::Vector3d& col_dir,
                               const std::vector<Eigen::Vector3d>& positions, const std::string& source,
                               double tolerance_mm = -1.0);

// Resamples an uneven stack to even slices along step_direction by linear interpolation between the
// two bracketing slices. `slices` is the volume in sorted order on stack.geometry(...); the result
// spans the same first and last slice with a step of at most the smallest gap
// (n' = ceil(extent / min_gap) + 1). The first and last slices are copied exactly.
Volume<float> resample_even_slices(const Volume<float>& slices, const SliceStack& stack);

}  // namespace ctsurg
