// The medial-atom vessel model (sim/vessel/, docs/vessel.md): what a step and a frame's surface cost as
// the vessel grows from 100 to 10,000 atoms (issue 20: "the vessel model's time per step for 100 to
// 10,000 atoms").
//   BM_VesselStep/N     one implicit step (1/60 s, at most 6 Gauss-Newton iterations, one sparse
//                       factorisation each) of a straight vessel of N atoms 1 mm apart, r 2 mm, wall 0.4 mm,
//                       E 1 MPa, clamped at one end and sagging under gravity (a large, changing
//                       deformation, so every step iterates)
//   BM_VesselSurface/N/S  the tube surface redrawn from the atoms (S spokes per ring, rotation-minimising
//                       frames), once per output frame
// bench/run.sh vessel writes the table in docs/benchmarks.md.
#include "ctsurg/core/centerline_file.h"
#include "ctsurg/sim/vessel/vessel_engine.h"

#include <benchmark/benchmark.h>

#include <memory>
#include <vector>

namespace {

using namespace ctsurg::sim;

std::unique_ptr<VesselEngine> straight_vessel(int atoms, int spokes) {
  ctsurg::Centerline c;
  for (int i = 0; i < atoms; ++i) {
    c.points.insert(c.points.end(), {static_cast<double>(i), 0.0, 0.0});
    c.radius.push_back(2.0);
  }
  c.branch_offsets = {0, atoms};
  c.branch_nodes = {0, 1};
  c.nodes = {0, 0, 0, static_cast<double>(atoms - 1), 0, 0};
  VesselWall wall;
  wall.youngs_modulus_pa = 1e6;
  wall.thickness_mm = 0.4;
  VesselChain chain = build_vessel_chain(c, {0, 0, 0}, wall, "bench");
  const std::vector<int32_t> fixed{chain.branch_atoms[0], chain.branch_atoms[1]};  // the first segment: a clamp
  VesselEngineOptions o;
  o.gravity = {0, 0, -9810};
  o.mass_damping = 5;
  o.spokes = spokes;
  return std::make_unique<VesselEngine>(std::move(chain), fixed, Vec3{0, 0, 0}, o);
}

void BM_VesselStep(benchmark::State& state) {
  const auto engine = straight_vessel(static_cast<int>(state.range(0)), 16);
  const std::vector<ToolInput> tools;
  const int64_t steps0 = engine->steps();
  for (auto _ : state) {
    const StabilityReport r = engine->step(tools, 1);
    if (!r.stable) state.SkipWithError("unstable step");
  }
  state.counters["atoms"] = static_cast<double>(state.range(0));
  state.counters["dt_ms"] = 1e3 * engine->dt();
  state.counters["realtime_factor"] = benchmark::Counter(engine->dt() * static_cast<double>(engine->steps() - steps0),
                                                         benchmark::Counter::kIsRate);
}
BENCHMARK(BM_VesselStep)->Arg(100)->Arg(1000)->Arg(10000)->Unit(benchmark::kMillisecond);

void BM_VesselSurface(benchmark::State& state) {
  const auto engine = straight_vessel(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  const std::vector<ToolInput> tools;
  for (int i = 0; i < 10; ++i) engine->step(tools, 1);  // bent, so the frames turn
  std::vector<float> xyz;
  for (auto _ : state) {
    engine->surface_vertices(xyz);
    benchmark::DoNotOptimize(xyz.data());
  }
  state.counters["atoms"] = static_cast<double>(state.range(0));
  state.counters["vertices"] = static_cast<double>(xyz.size() / 3);
}
BENCHMARK(BM_VesselSurface)->Args({100, 16})->Args({1000, 16})->Args({10000, 16})->Args({1000, 64})->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
