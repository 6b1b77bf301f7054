// Morphological clean-up of a tissue mask at full CT resolution (ITK is confined to
// mask_cleanup.cpp). Steps, in this order, each optional:
//   1. closing with a ball of radius closing_mm (per label; closes gaps and cracks),
//   2. filling of internal holes (per label; a hole is background not connected to the volume
//      border through 6-connected background voxels),
//   3. connected components of the union of all labels (26-connectivity): keep only the largest,
//      and/or drop components smaller than min_component_mm3.
// Per-label steps never overwrite voxels of another label: voxels a step adds are taken only where
// the mask is still background, lower label ids first.
#pragma once

#include "ctsurg/core/volume.h"

#include <cstdint>

namespace ctsurg {

struct MaskCleanupOptions {
  double closing_mm = 0.0;         // ball radius in mm (0: no closing); per axis round(r / spacing) voxels
  bool fill_holes = false;         // fill internal holes
  bool keep_largest = false;       // keep only the largest 26-connected component
  double min_component_mm3 = 0.0;  // drop components with less volume (0: keep all)
};

// mask: label mask (0 = background) on any lattice with positive spacing; spacing in mm is used
// for the closing radius and the component volumes. Returns a mask on the same lattice.
// Deterministic: equal-size components are ranked by their first voxel in memory order.
Volume<uint16_t> cleanup_mask(const Volume<uint16_t>& mask, const MaskCleanupOptions& options);

}  // namespace ctsurg
