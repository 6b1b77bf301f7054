// The bundled heart as the spring-mass benchmarks run it: the heart mask's occupancy grid with 2.4 mm
// cells, as ctsurg-grid makes it (48,789 particles, the papers' pig-heart scale), springs of a
// myocardium-like stiffness. Built once per program (bench_spring_models, bench_instruments).
#pragma once

#include "ctsurg/preprocess/image_file_reader.h"
#include "ctsurg/preprocess/occupancy_downsampling.h"
#include "ctsurg/sim/springs/spring_grid_model.h"

#include <algorithm>
#include <filesystem>

namespace ctsurg::bench {

// ~ E h for E = 30 kPa (myocardium-like) and h = 2.4 mm, g/s^2.
inline sim::SpringGridMaterial heart_spring_material() {
  sim::SpringGridMaterial m;
  m.face_stiffness = 7.2e4;
  m.edge_stiffness = 3.6e4;
  return m;
}

inline const sim::SpringGridModel& heart_spring_model() {
  static const sim::SpringGridModel model = [] {
    const auto v = read_image_file(std::filesystem::path(CTSURG_SOURCE_DIR) / "data_samples" / "heart" / "heart_mask.nii.gz");
    Volume<uint16_t> mask(v.geometry);
    std::transform(v.voxels.begin(), v.voxels.end(), mask.voxels.begin(), [](float x) { return uint16_t(x > 0.5f); });
    OccupancyDownsamplingOptions options;
    options.cell_mm = 2.4;
    return sim::build_spring_grid_model(downsample_occupancy(mask, options, {{1, "heart"}}), heart_spring_material());
  }();
  return model;
}

}  // namespace ctsurg::bench
