// Marching cubes (mesh/marching_cubes.h) on the bundled heart, 1 and 2 threads: the CT at 150 HU
// (contrast-filled blood pool and bone; 1.4 M nodes) and the occupancy grid's volume fractions at
// iso 0.5 (the surface the pipeline simulates), at the papers' 2.4 mm cells and at 1.0 mm cells.
// Reports lattice nodes per second (items_per_second) and the mesh size. bench/run.sh runs it next
// to VTK's vtkFlyingEdges3D on the same fields (tests/peers/flying_edges_peer.py) and writes both
// to docs/benchmarks.md.
#include "ctsurg/mesh/marching_cubes.h"
#include "ctsurg/preprocess/ct_import.h"
#include "ctsurg/preprocess/image_file_reader.h"
#include "ctsurg/preprocess/occupancy_downsampling.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <filesystem>
#include <map>

namespace {

const std::filesystem::path kHeart = std::filesystem::path(CTSURG_SOURCE_DIR) / "data_samples" / "heart";

const ctsurg::Volume<float>& heart_ct() {
  static const ctsurg::Volume<float> ct = ctsurg::import_ct((kHeart / "heart_ct.nii.gz").string(), {}).volume.hu;
  return ct;
}

// The fractional occupancy grid of the heart mask with `cell_mm` cells, as ctsurg-grid makes it.
const ctsurg::Volume<float>& heart_grid(int cell_tenths_mm) {
  static std::map<int, ctsurg::Volume<float>> grids;
  auto it = grids.find(cell_tenths_mm);
  if (it != grids.end()) return it->second;
  const auto v = ctsurg::read_image_file(kHeart / "heart_mask.nii.gz");
  ctsurg::Volume<uint16_t> mask(v.geometry);
  std::transform(v.voxels.begin(), v.voxels.end(), mask.voxels.begin(), [](float x) { return uint16_t(x > 0.5f); });
  ctsurg::OccupancyDownsamplingOptions options;
  options.cell_mm = cell_tenths_mm / 10.0;
  return grids.emplace(cell_tenths_mm, ctsurg::downsample_occupancy(mask, options, {{1, "heart"}}).fraction).first->second;
}

void run(benchmark::State& state, const ctsurg::Volume<float>& field, double iso) {
  const int threads = static_cast<int>(state.range(0));
  int64_t triangles = 0;
  for (auto _ : state) {
    const auto mesh = ctsurg::marching_cubes(field, iso, {threads});
    triangles = mesh.triangle_count();
    benchmark::DoNotOptimize(mesh.vertices.data());
  }
  state.SetItemsProcessed(state.iterations() * field.geometry.voxel_count());
  state.counters["nodes"] = static_cast<double>(field.geometry.voxel_count());
  state.counters["triangles"] = static_cast<double>(triangles);
  state.counters["threads"] = threads;
}

void BM_MarchingCubesHeartCt150HU(benchmark::State& state) { run(state, heart_ct(), 150.0); }
void BM_MarchingCubesHeartGrid2_4mm(benchmark::State& state) { run(state, heart_grid(24), 0.5); }
void BM_MarchingCubesHeartGrid1_0mm(benchmark::State& state) { run(state, heart_grid(10), 0.5); }
BENCHMARK(BM_MarchingCubesHeartCt150HU)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_MarchingCubesHeartGrid2_4mm)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_MarchingCubesHeartGrid1_0mm)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
