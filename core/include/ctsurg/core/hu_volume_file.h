// The HU volume file written by ctsurg-import and read by ctsurg-grid, ctsurg-normalmap, ...
//
//   /provenance           (provenance.h)
//   /hu                   volume (volume_hdf5.h), quantity "HU", units "HU"; int16 when exact, else float32
//   /source               attributes describing the scan: format, series_uid, modality, notes (JSON)
//
// plus an XDMF sidecar. See docs/formats.md.
#pragma once

#include "ctsurg/core/provenance.h"
#include "ctsurg/core/volume.h"

#include <filesystem>
#include <nlohmann/json.hpp>

namespace ctsurg {

struct HuVolume {
  Volume<float> hu;                   // Hounsfield units; every value finite
  nlohmann::json source = nlohmann::json::object();  // format, series UID, warnings... (free-form)
};

// Smallest exact storage for the HU values: Int16 when all are integers in [-32768, 32767].
VoxelType exact_hu_storage(const Volume<float>& hu);

// Writes `path` (and its .xdmf sidecar) atomically.
void write_hu_volume_file(const std::filesystem::path& path, const HuVolume& volume, const Provenance& provenance);
// Reads an HU volume file; InputError naming the file and object when it is not one.
HuVolume read_hu_volume_file(const std::filesystem::path& path);

}  // namespace ctsurg
