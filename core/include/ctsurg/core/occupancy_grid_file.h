// The occupancy grid: which cells of a coarse, isotropic lattice over the organ become particles,
// how much of each cell the tissue fills, and which tissue it is; plus the full-resolution tissue
// labels it came from (for the mesh stage). Written by ctsurg-grid.
//
//   /provenance
//   /grid/occupancy   volume uint8, 1 = the cell is a particle (fraction >= threshold), else 0
//   /grid/fraction    volume float32 in [0,1], volume fraction of the cell inside the tissue
//   /grid/label       volume uint16, dominant tissue label in the cell (0 = none)
//   /mask             volume uint16 at full CT resolution, tissue label per voxel (0 = background)
//   /grid attributes: cell_mm, occupancy_threshold, particles (count), labels (JSON: id -> name)
#pragma once

#include "ctsurg/core/atomic_output.h"
#include "ctsurg/core/provenance.h"
#include "ctsurg/core/volume.h"

#include <filesystem>
#include <map>
#include <string>

namespace ctsurg {

struct OccupancyGrid {
  Volume<uint8_t> occupancy;   // cell lattice; geometry: cell centres, spacing = cell size (isotropic)
  Volume<float> fraction;      // same lattice
  Volume<uint16_t> label;      // same lattice
  Volume<uint16_t> mask;       // full-resolution lattice of the CT
  double occupancy_threshold = 0.5;
  std::map<uint16_t, std::string> label_names;  // tissue names, e.g. {1: "heart"}

  int64_t particle_count() const;
};

void write_occupancy_grid_file(const std::filesystem::path& path, const OccupancyGrid& grid,
                               const Provenance& provenance, OutputUnit* unit = nullptr);
OccupancyGrid read_occupancy_grid_file(const std::filesystem::path& path);

}  // namespace ctsurg
