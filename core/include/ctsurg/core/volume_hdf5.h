// Volumes in ctsurg HDF5 files. A volume is a group holding one dataset "data" of shape
// (nk, nj, ni) in C order (so i, i.e. x, is fastest, as in memory) and its geometry as attributes:
//   dims [ni, nj, nk] int64, spacing_mm [3], origin_mm [3] (LPS), direction [9] (row-major 3x3,
//   columns are the index axes' LPS directions), frame "LPS", quantity, units.
// See docs/formats.md.
#pragma once

#include "ctsurg/core/hdf5_file.h"
#include "ctsurg/core/volume.h"

#include <string>

namespace ctsurg {

struct VolumeMeta {
  std::string quantity;  // "HU", "occupancy", "fraction", "label", "mask"
  std::string units;     // "HU", "1", "volume fraction", ...
};

// Writes `volume` as group `name` under `parent`, converting the voxels to `stored` on the way
// (values must be representable; the caller chooses). T is uint8_t, int16_t, uint16_t, int32_t or
// float.
template <class T>
void write_volume(h5::Group& parent, const std::string& name, const Volume<T>& volume, const VolumeMeta& meta,
                  VoxelType stored);

// Reads group `name` under `parent`, converting stored voxels to T, and validates the geometry.
template <class T>
Volume<T> read_volume(const h5::Group& parent, const std::string& name);

// Geometry and metadata only, without reading voxels.
ImageGeometry read_volume_geometry(const h5::Group& parent, const std::string& name);
VolumeMeta read_volume_meta(const h5::Group& parent, const std::string& name);

}  // namespace ctsurg
