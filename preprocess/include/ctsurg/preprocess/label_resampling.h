// Nearest-neighbour resampling of a label volume onto another lattice. Labels are never
// interpolated. The common case is a mask on the same voxels as the CT but stored in another index
// order (e.g. a NIfTI written with the rows flipped, as dcm2niix and TotalSegmentator do): then
// every target voxel centre coincides with a source voxel centre and the result is exact.
#pragma once

#include "ctsurg/core/volume.h"

#include <cstdint>

namespace ctsurg {

struct LabelResampling {
  Volume<uint16_t> labels;     // on the target lattice
  double max_offset_mm = 0.0;  // largest distance from a target voxel centre to the source voxel used
  int64_t outside = 0;         // target voxels that fall outside the source volume (labelled 0)
  bool exact() const { return max_offset_mm < 1e-3; }
};

// `source`: labels on their own lattice. `target`: the lattice to put them on (LPS mm).
LabelResampling resample_labels_nearest(const Volume<uint16_t>& source, const ImageGeometry& target);

}  // namespace ctsurg
