// DeviceSimulation throughput (sim/device_simulation.h, docs/gpu.md): iterations (time steps) per
// second of the implicit grid model and of the explicit CSR springs on a CUDA device, on solid blocks
// of 2.4 mm cells at the spring-mass papers' Table 1 sizes (10k .. 100k particles; Mosegaard & Sorensen
// 2005) and at 1M and 10M particles (explicit springs up to 1M: the host-side model of 10M would need
// ~8 GB). One iteration = one step (forces gathered per particle, Verlet, gravity, Verlet damping; no
// spring damping, no normals), as bench_spring_models.cpp on the CPU. Steps run in batches of 480 per
// timed call (CUDA graph replays), then the device is synchronised.
//
// Effective bandwidth: the bytes one step must move per particle, if every array is read once,
// neighbours' positions come from cache, and nothing else is moved:
//   grid:     x, y, z, px, py, pz (24) + inverse mass (4) + spring mask (4) + 18 neighbour ids (72)
//             read, next x, y, z (12) written: kGridBytes = 116 B per particle per step;
//   explicit: x, y, z, px, py, pz (24) + inverse mass (4) + row offset (4) read, next (12) written: 44 B
//             per particle, plus per row entry neighbour and spring ids (8), stiffness and rest length
//             (8), alive flag (1): 17 B per entry (each spring's data is read from both its rows).
// GB/s = bytes x particles x steps / s, and "of peak" divides by the device's peak bandwidth (2 x
// memory clock x bus width, from the CUDA runtime). bench/gpu/run.sh turns the JSON into the table
// for docs/benchmarks.md.
//
// Without a CUDA device (or in a build without CUDA) the program says so and exits 0.
#include "ctsurg/sim/base/backend.h"
#include "ctsurg/sim/springs/device_simulation.h"
#include "ctsurg/sim/springs/explicit_spring_model.h"
#include "ctsurg/sim/springs/spring_grid_model.h"
#include "ctsurg/sim/springs/spring_mass_step.h"
#include "ctsurg/sim/springs/stability.h"

#include "device_bench_main.h"

#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>

namespace {

using namespace ctsurg::sim;

constexpr double kGridBytes = 116;
constexpr double kExplicitParticleBytes = 44, kExplicitEntryBytes = 17;
constexpr int64_t kBatch = 480;  // steps per timed call: 10 graph replays

SpringGridMaterial material() {
  SpringGridMaterial m;
  m.face_stiffness = 7.2e4;  // as bench_spring_models.cpp: ~ E h for E = 30 kPa, h = 2.4 mm, g/s^2
  m.edge_stiffness = 3.6e4;
  return m;
}

// A solid block of about `particles` cells (dimensions chosen so the count is within 1%).
const SpringGridModel& block_model(int64_t particles) {
  static std::map<int64_t, std::unique_ptr<SpringGridModel>> models;
  auto& slot = models[particles];
  if (!slot) {
    static const std::map<int64_t, std::array<int, 3>> dims{
        {10000, {25, 20, 20}},    {25000, {25, 25, 40}},      {50000, {50, 40, 25}},
        {100000, {50, 50, 40}},   {1000000, {100, 100, 100}}, {10000000, {216, 216, 215}}};
    const auto d = dims.at(particles);
    ctsurg::ImageGeometry g;
    g.dims = {d[0], d[1], d[2]};
    g.spacing = Eigen::Vector3d(2.4, 2.4, 2.4);
    slot = std::make_unique<SpringGridModel>(build_spring_grid_model(ctsurg::Volume<uint8_t>(g, 1), material()));
  }
  return *slot;
}

const ExplicitSpringModel& explicit_block_model(int64_t particles) {
  static std::map<int64_t, std::unique_ptr<ExplicitSpringModel>> models;
  auto& slot = models[particles];
  if (!slot) slot = std::make_unique<ExplicitSpringModel>(explicit_model_from_grid(block_model(particles)));
  return *slot;
}

DeviceSimulation& device() {
  static DeviceSimulation simulation;
  return simulation;
}

double peak_gbs() {
  static const double peak = device().device_info().peak_bandwidth_gbs;
  return peak;
}

template <class Model>
void run(benchmark::State& state, const Model& model, const SpringGridModel& grid, double bytes_per_particle) {
  auto particles = model.make_state();
  StepParameters p;
  p.dt = critical_time_step(grid).dt;
  p.damping = 0.01;
  p.gravity = {0, 0, -9810};
  DeviceSimulation& gpu = device();
  gpu.upload(model, particles);
  gpu.step(kBatch, p);  // warm-up: graph capture, caches
  gpu.synchronize();
  for (auto _ : state) {
    gpu.step(kBatch, p);
    gpu.synchronize();
  }
  const double n = model.particle_count();
  const double steps = static_cast<double>(state.iterations()) * kBatch;
  state.SetItemsProcessed(static_cast<int64_t>(steps));  // items_per_second = iterations (steps) per second
  state.counters["particles"] = n;
  state.counters["bytes_per_particle"] = bytes_per_particle;
  state.counters["GB/s"] = benchmark::Counter(bytes_per_particle * n * steps / 1e9, benchmark::Counter::kIsRate);
  state.counters["peak_GB/s"] = peak_gbs();
  state.counters["particle_updates/s"] = benchmark::Counter(n * steps, benchmark::Counter::kIsRate);
}

void BM_DeviceGridStep(benchmark::State& state) {
  const SpringGridModel& model = block_model(state.range(0));
  run(state, model, model, kGridBytes);
}

void BM_DeviceExplicitStep(benchmark::State& state) {
  const SpringGridModel& grid = block_model(state.range(0));
  const ExplicitSpringModel& model = explicit_block_model(state.range(0));
  const double entries_per_particle = static_cast<double>(model.row_neighbour.size()) / model.particle_count();
  run(state, model, grid, kExplicitParticleBytes + kExplicitEntryBytes * entries_per_particle);
}

BENCHMARK(BM_DeviceGridStep)
    ->Arg(10000)->Arg(25000)->Arg(50000)->Arg(100000)->Arg(1000000)->Arg(10000000)
    ->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_DeviceExplicitStep)
    ->Arg(10000)->Arg(25000)->Arg(50000)->Arg(100000)->Arg(1000000)
    ->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

int main(int argc, char** argv) { return ctsurg::sim::bench::run_device_benchmarks("bench_device_simulation", argc, argv); }
