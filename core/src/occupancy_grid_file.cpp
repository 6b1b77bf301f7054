#include "ctsurg/core/occupancy_grid_file.h"

#include "ctsurg/core/atomic_output.h"
#include "ctsurg/core/error.h"
#include "ctsurg/core/hdf5_file.h"
#include "ctsurg/core/volume_hdf5.h"
#include "ctsurg/core/xdmf_sidecar.h"

#include <algorithm>
#include <cstdio>
#include <nlohmann/json.hpp>

namespace ctsurg {

int64_t OccupancyGrid::particle_count() const {
  return std::count(occupancy.voxels.begin(), occupancy.voxels.end(), uint8_t{1});
}

void write_occupancy_grid_file(const std::filesystem::path& path, const OccupancyGrid& grid,
                               const Provenance& provenance) {
  AtomicOutput out(path);
  AtomicOutput sidecar(xdmf_path_for(path));
  {
    h5::File f = h5::File::create(out.temp_path(), path.string());
    h5::Group root = f.root();
    root.set_attribute("ctsurg_format", std::string("occupancy_grid"));
    root.set_attribute("ctsurg_format_version", int64_t{1});
    provenance.write(root);
    h5::Group g = root.create_group("grid");
    g.set_attribute("cell_mm", grid.occupancy.geometry.spacing[0]);
    g.set_attribute("occupancy_threshold", grid.occupancy_threshold);
    g.set_attribute("particles", grid.particle_count());
    nlohmann::json names = nlohmann::json::object();
    for (const auto& [id, name] : grid.label_names) names[std::to_string(id)] = name;
    g.set_attribute("labels", names.dump());
    write_volume(g, "occupancy", grid.occupancy, {"occupancy", "1"}, VoxelType::UInt8);
    write_volume(g, "fraction", grid.fraction, {"fraction", "volume fraction"}, VoxelType::Float32);
    write_volume(g, "label", grid.label, {"label", "tissue label"}, VoxelType::UInt16);
    write_volume(root, "mask", grid.mask, {"label", "tissue label"}, VoxelType::UInt16);
    f.close();
  }
  const std::string xml = xdmf_document(
      path.filename().string(),
      {{"grid",
        grid.occupancy.geometry,
        {{"occupancy", "/grid/occupancy/data", VoxelType::UInt8},
         {"fraction", "/grid/fraction/data", VoxelType::Float32},
         {"label", "/grid/label/data", VoxelType::UInt16}}},
       {"mask", grid.mask.geometry, {{"mask", "/mask/data", VoxelType::UInt16}}}});
  {
    std::FILE* fp = std::fopen(sidecar.temp_path().c_str(), "wb");
    if (!fp) throw RuntimeError(sidecar.path().string() + ": cannot write");
    std::fwrite(xml.data(), 1, xml.size(), fp);
    std::fclose(fp);
  }
  out.commit();
  sidecar.commit();
}

OccupancyGrid read_occupancy_grid_file(const std::filesystem::path& path) {
  const h5::File f = h5::File::open(path);
  const h5::Group root = f.root();
  if (!root.has_attribute("ctsurg_format") || root.string_attribute("ctsurg_format") != "occupancy_grid") {
    throw InputError(path.string(), "/@ctsurg_format", "not a ctsurg occupancy grid file (expected 'occupancy_grid')");
  }
  OccupancyGrid grid;
  const h5::Group g = root.open_group("grid");
  grid.occupancy = read_volume<uint8_t>(g, "occupancy");
  grid.fraction = read_volume<float>(g, "fraction");
  grid.label = read_volume<uint16_t>(g, "label");
  grid.mask = read_volume<uint16_t>(root, "mask");
  grid.occupancy_threshold = g.double_attribute("occupancy_threshold");
  const auto names = nlohmann::json::parse(g.string_attribute("labels"), nullptr, false);
  if (names.is_object()) {
    for (const auto& [k, v] : names.items()) grid.label_names[static_cast<uint16_t>(std::stoi(k))] = v.get<std::string>();
  }
  for (const auto* lattice : {&grid.fraction.geometry, &grid.label.geometry}) {
    if (!lattice->same_lattice(grid.occupancy.geometry, 1e-6)) {
      throw InputError(path.string(), "/grid", "fraction/label lattices differ from the occupancy lattice");
    }
  }
  return grid;
}

}  // namespace ctsurg
