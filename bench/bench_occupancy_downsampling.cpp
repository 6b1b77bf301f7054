// Throughput of the grid step's core: exact fractional occupancy of a full-resolution mask on a
// coarse cell lattice (downsample_occupancy), on the bundled heart mask. Reports full-resolution
// voxels per second (items_per_second) and the particle count, at the papers' 2.4 mm cells and at
// finer cells. Run by bench/run.sh; the results go to docs/benchmarks.md.
#include "ctsurg/preprocess/image_file_reader.h"
#include "ctsurg/preprocess/occupancy_downsampling.h"

#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <filesystem>

namespace {

const ctsurg::Volume<uint16_t>& heart_mask() {
  static const ctsurg::Volume<uint16_t> mask = [] {
    const auto file = std::filesystem::path(CTSURG_SOURCE_DIR) / "data_samples" / "heart" / "heart_mask.nii.gz";
    const auto v = ctsurg::read_image_file(file);
    ctsurg::Volume<uint16_t> m(v.geometry);
    std::transform(v.voxels.begin(), v.voxels.end(), m.voxels.begin(), [](float x) { return uint16_t(x > 0.5f); });
    return m;
  }();
  return mask;
}

void BM_DownsampleHeart(benchmark::State& state) {
  const auto& mask = heart_mask();
  ctsurg::OccupancyDownsamplingOptions options;
  options.cell_mm = double(state.range(0)) / 10.0;
  options.keep_largest_only = true;
  omp_set_num_threads(static_cast<int>(state.range(1)));
  int64_t particles = 0;
  for (auto _ : state) {
    const auto grid = ctsurg::downsample_occupancy(mask, options, {{1, "heart"}});
    particles = grid.particle_count();
    benchmark::DoNotOptimize(particles);
  }
  state.SetItemsProcessed(state.iterations() * mask.geometry.voxel_count());
  state.counters["particles"] = double(particles);
  state.counters["cell_mm"] = options.cell_mm;
}

}  // namespace

BENCHMARK(BM_DownsampleHeart)
    ->ArgNames({"cell_mm_x10", "threads"})
    ->Args({24, 1})
    ->Args({24, 2})
    ->Args({15, 2})
    ->Args({10, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

BENCHMARK_MAIN();
