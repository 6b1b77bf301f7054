// Marching cubes (mesh/marching_cubes.h) on the bundled heart CT at 150 HU (contrast-filled blood
// pool and bone), 1 and 2 threads. Reports voxels (lattice nodes) per second and the mesh size.
#include "ctsurg/mesh/marching_cubes.h"
#include "ctsurg/preprocess/ct_import.h"

#include <benchmark/benchmark.h>

#include <filesystem>

namespace {

const ctsurg::Volume<float>& heart_ct() {
  static const ctsurg::Volume<float> ct = [] {
    const auto file = std::filesystem::path(CTSURG_SOURCE_DIR) / "data_samples" / "heart" / "heart_ct.nii.gz";
    return ctsurg::import_ct(file.string(), {}).volume.hu;
  }();
  return ct;
}

void BM_MarchingCubesHeart150HU(benchmark::State& state) {
  const auto& ct = heart_ct();
  const int threads = static_cast<int>(state.range(0));
  int64_t triangles = 0;
  for (auto _ : state) {
    const auto mesh = ctsurg::marching_cubes(ct, 150.0, {threads});
    triangles = mesh.triangle_count();
    benchmark::DoNotOptimize(mesh.vertices.data());
  }
  state.SetItemsProcessed(state.iterations() * ct.geometry.voxel_count());
  state.counters["triangles"] = static_cast<double>(triangles);
  state.counters["threads"] = threads;
}
BENCHMARK(BM_MarchingCubesHeart150HU)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
