#include "ctsurg/core/occupancy_grid_file.h"

#include "ctsurg/core/ctsurg_file.h"
#include "ctsurg/core/error.h"
#include "ctsurg/core/hdf5_file.h"
#include "ctsurg/core/volume_hdf5.h"

#include <algorithm>
#include <nlohmann/json.hpp>

namespace ctsurg {

int64_t OccupancyGrid::particle_count() const {
  return std::count(occupancy.voxels.begin(), occupancy.voxels.end(), uint8_t{1});
}

void write_occupancy_grid_file(const std::filesystem::path& path, const OccupancyGrid& grid,
                               const Provenance& provenance, OutputUnit* unit) {
  write_ctsurg_file(
      path, "occupancy_grid", 1, provenance,
      [&](h5::Group& root) {
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
      },
      {{"grid",
        grid.occupancy.geometry,
        {{"occupancy", "/grid/occupancy/data", VoxelType::UInt8},
         {"fraction", "/grid/fraction/data", VoxelType::Float32},
         {"label", "/grid/label/data", VoxelType::UInt16}}},
       {"mask", grid.mask.geometry, {{"mask", "/mask/data", VoxelType::UInt16}}}}, unit);
}

OccupancyGrid read_occupancy_grid_file(const std::filesystem::path& path) {
  const h5::File f = open_ctsurg_file(path, "occupancy_grid");
  const h5::Group root = f.root();
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
