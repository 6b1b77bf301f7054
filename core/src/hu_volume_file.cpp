#include "ctsurg/core/hu_volume_file.h"

#include "ctsurg/core/ctsurg_file.h"
#include "ctsurg/core/error.h"
#include "ctsurg/core/hdf5_file.h"
#include "ctsurg/core/volume_hdf5.h"

#include <cmath>

namespace ctsurg {

VoxelType exact_hu_storage(const Volume<float>& hu) {
  for (const float v : hu.voxels) {
    if (v != std::nearbyint(v) || v < -32768.0f || v > 32767.0f) return VoxelType::Float32;
  }
  return VoxelType::Int16;
}

void write_hu_volume_file(const std::filesystem::path& path, const HuVolume& volume, const Provenance& provenance) {
  const VoxelType stored = exact_hu_storage(volume.hu);
  write_ctsurg_file(
      path, "hu_volume", 1, provenance,
      [&](h5::Group& root) {
        write_volume(root, "hu", volume.hu, {"HU", "HU"}, stored);
        root.create_group("source").set_attribute("json", volume.source.dump());
      },
      {{"ct", volume.hu.geometry, {{"HU", "/hu/data", stored}}}});
}

HuVolume read_hu_volume_file(const std::filesystem::path& path) {
  const h5::File f = open_ctsurg_file(path, "hu_volume");
  const h5::Group root = f.root();
  HuVolume v;
  v.hu = read_volume<float>(root, "hu");
  if (root.has("source")) {
    v.source = nlohmann::json::parse(root.open_group("source").string_attribute("json"), nullptr, false);
  }
  return v;
}

}  // namespace ctsurg
