#include "ctsurg/core/hu_volume_file.h"

#include "ctsurg/core/atomic_output.h"
#include "ctsurg/core/error.h"
#include "ctsurg/core/hdf5_file.h"
#include "ctsurg/core/volume_hdf5.h"
#include "ctsurg/core/xdmf_sidecar.h"

#include <cmath>
#include <cstdio>

namespace ctsurg {

VoxelType exact_hu_storage(const Volume<float>& hu) {
  for (const float v : hu.voxels) {
    if (v != std::nearbyint(v) || v < -32768.0f || v > 32767.0f) return VoxelType::Float32;
  }
  return VoxelType::Int16;
}

void write_hu_volume_file(const std::filesystem::path& path, const HuVolume& volume, const Provenance& provenance) {
  AtomicOutput out(path);
  AtomicOutput sidecar(xdmf_path_for(path));
  const VoxelType stored = exact_hu_storage(volume.hu);
  {
    h5::File f = h5::File::create(out.temp_path(), path.string());
    h5::Group root = f.root();
    root.set_attribute("ctsurg_format", std::string("hu_volume"));
    root.set_attribute("ctsurg_format_version", int64_t{1});
    provenance.write(root);
    write_volume(root, "hu", volume.hu, {"HU", "HU"}, stored);
    h5::Group source = root.create_group("source");
    source.set_attribute("json", volume.source.dump());
    f.close();
  }
  const std::string xml = xdmf_document(path.filename().string(),
                                        {{"ct", volume.hu.geometry, {{"HU", "/hu/data", stored}}}});
  {
    std::FILE* fp = std::fopen(sidecar.temp_path().c_str(), "wb");
    if (!fp) throw RuntimeError(sidecar.path().string() + ": cannot write");
    std::fwrite(xml.data(), 1, xml.size(), fp);
    std::fclose(fp);
  }
  out.commit();
  sidecar.commit();
}

HuVolume read_hu_volume_file(const std::filesystem::path& path) {
  const h5::File f = h5::File::open(path);
  const h5::Group root = f.root();
  if (!root.has_attribute("ctsurg_format") || root.string_attribute("ctsurg_format") != "hu_volume") {
    throw InputError(path.string(), "/@ctsurg_format", "not a ctsurg HU volume file (expected 'hu_volume')");
  }
  HuVolume v;
  v.hu = read_volume<float>(root, "hu");
  if (root.has("source")) {
    v.source = nlohmann::json::parse(root.open_group("source").string_attribute("json"), nullptr, false);
  }
  return v;
}

}  // namespace ctsurg
