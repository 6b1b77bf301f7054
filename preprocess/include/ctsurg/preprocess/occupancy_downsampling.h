// Downsampling a full-resolution tissue mask to the occupancy grid of the spring-mass model: a
// lattice of cubic cells of edge h (mm) over the mask's bounding box, each cell holding the exact
// volume fraction of tissue inside it, its dominant tissue label, and whether it becomes a particle.
//
// Lattice: same direction matrix as the CT, spacing h on all three axes. Along each index axis the
// cells cover the bounding box of the mask's voxel boxes (voxel i spans [(i - 1/2) s, (i + 1/2) s]
// along that axis, s = CT spacing), centred on it, plus one empty margin cell on each side.
//
// Fraction: voxels are treated as boxes, so the tissue volume inside a cell is
//   V(cell) = sum over tissue voxels v of |box(v) ∩ cell| = sum_v prod_a overlap_a(c_a, v_a),
// which factorises per axis. The per-axis overlap lengths (a sparse cells x voxels matrix per axis)
// are applied one axis after the other (x, then y, then z), so the cost is linear in the number of
// voxels even when h is not a multiple of the voxel spacing. fraction = V(cell) / h^3.
// Label: the label with the largest volume in the cell (ties: the lowest id), 0 for empty cells,
// kept also for cells that are not particles.
// Particles: fraction >= occupancy_threshold; then 18-connected components of the particles (the
// spring-mass model links each cell to its 18 neighbours) that cannot form a body are dropped:
// single isolated cells always, components below min_component_mm3 (as cells x h^3), and with
// keep_largest_only every component but the largest (ties: the first in memory order).
#pragma once

#include "ctsurg/core/occupancy_grid_file.h"
#include "ctsurg/core/volume.h"

#include <array>
#include <cstdint>
#include <map>
#include <string>

namespace ctsurg {

// Inclusive voxel index box [lo, hi] per axis.
struct IndexBox {
  std::array<int64_t, 3> lo{0, 0, 0};
  std::array<int64_t, 3> hi{-1, -1, -1};
  bool empty() const { return hi[0] < lo[0] || hi[1] < lo[1] || hi[2] < lo[2]; }
};

// Bounding box of the non-zero voxels of `mask` (empty box when there are none).
IndexBox mask_bounding_box(const Volume<uint16_t>& mask);
// Bounding box of the voxels equal to `label` (label 0: of all non-zero voxels).
IndexBox label_bounding_box(const Volume<uint16_t>& mask, uint16_t label);

struct OccupancyDownsamplingOptions {
  double cell_mm = 0.0;              // cell edge h, mm; 0 to derive it from max_dim
  int64_t max_dim = 0;               // cells along the bounding box's longest axis (margin excluded)
  double occupancy_threshold = 0.5;  // a cell is a particle when fraction >= this, in (0, 1]
  bool keep_largest_only = false;    // keep only the largest 18-connected particle component
  double min_component_mm3 = 0.0;    // drop particle components with cells x h^3 below this
};

// The cell edge in mm the options ask for over `box` of lattice `ct`: cell_mm, or the longest
// box extent (mm) / max_dim. InputError("--voxel-mm" / "--max-dim", ...) when both or neither is
// set, or when the value is not positive and finite.
double occupancy_cell_size(const ImageGeometry& ct, const IndexBox& box, const OccupancyDownsamplingOptions& options);

// The cell lattice (cell centres, spacing h, direction of `ct`) covering `box` plus a one-cell
// margin, as described above. InputError(option, "grid", ...) when the lattice would be absurdly
// large (more cells than memory allows; checked before allocating); `option` names the option that
// set h in the message.
ImageGeometry occupancy_cell_lattice(const ImageGeometry& ct, const IndexBox& box, double cell_mm,
                                     const std::string& option = "--voxel-mm");

// Volume fraction (in [0, 1]) of every cell of `cells` inside the voxels of `mask` equal to
// `label` (label 0: all non-zero voxels). cells must share mask's direction (as
// occupancy_cell_lattice makes it). Returns a volume on `cells`.
Volume<double> tissue_volume_fraction(const Volume<uint16_t>& mask, const ImageGeometry& cells, uint16_t label = 0);

// Drops particles (occupancy 1) not in an 18-connected component that is kept (see above).
// occupancy: cell lattice, 0/1. Returns the number of particles dropped.
int64_t drop_unconnected_particles(Volume<uint8_t>& occupancy, bool keep_largest_only, int64_t min_cells);

// The whole downsampling: lattice, fraction, label, particles. `mask` is the full-resolution label
// mask on the CT lattice (copied into the result), label_names the names to store. InputError for
// bad options (see occupancy_cell_size), an empty mask ("mask", "empty"), or when no cell reaches
// the threshold ("--occupancy-threshold").
OccupancyGrid downsample_occupancy(const Volume<uint16_t>& mask, const OccupancyDownsamplingOptions& options,
                                   const std::map<uint16_t, std::string>& label_names);

}  // namespace ctsurg
