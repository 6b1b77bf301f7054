// Spring-mass step throughput (sim/spring_mass_step.h): iterations (time steps) per second of the
// implicit grid model and the explicit CSR model on the same 18-neighbour springs, at the particle
// counts of the spring-mass papers' Table 1 (Mosegaard & Sorensen 2005; Mosegaard, Herborg & Sorensen 2005:
// 10,000 .. 100,000 particles) on solid blocks, and on the bundled heart's occupancy grid at the
// papers' 2.4 mm-cell scale (their pig heart had 42,745 particles), 1 and 2 threads. One iteration =
// one step: spring forces gathered per particle, Verlet update, gravity, damping; no normals, no
// spring damping (as the papers' table). bench/run.sh writes the table in docs/benchmarks.md.
#include "ctsurg/sim/springs/explicit_spring_model.h"
#include "ctsurg/sim/springs/spring_grid_model.h"
#include "ctsurg/sim/springs/spring_mass_step.h"
#include "ctsurg/sim/springs/stability.h"
#include "heart_spring_model.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <memory>

namespace {

using namespace ctsurg::sim;

SpringGridMaterial material() { return ctsurg::bench::heart_spring_material(); }

// A solid block of about `particles` cells, 2.4 mm cells.
const SpringGridModel& block_model(int64_t particles) {
  static std::map<int64_t, std::unique_ptr<SpringGridModel>> models;
  auto& slot = models[particles];
  if (!slot) {
    static const std::map<int64_t, std::array<int, 3>> dims{{10000, {25, 20, 20}}, {20000, {25, 40, 20}},
                                                            {40000, {40, 40, 25}}, {50000, {50, 40, 25}},
                                                            {100000, {50, 50, 40}}};
    const auto d = dims.at(particles);
    ctsurg::ImageGeometry g;
    g.dims = {d[0], d[1], d[2]};
    g.spacing = Eigen::Vector3d(2.4, 2.4, 2.4);
    slot = std::make_unique<SpringGridModel>(
        build_spring_grid_model(ctsurg::Volume<uint8_t>(g, 1), material()));
  }
  return *slot;
}

const SpringGridModel& heart_model() { return ctsurg::bench::heart_spring_model(); }

template <class Model>
void run(benchmark::State& state, const Model& model, int threads, int64_t springs) {
  ParticleState s = model.make_state();
  StepParameters p;
  p.dt = critical_time_step(model).dt;
  p.damping = 0.01;
  p.gravity = {0, 0, -9810};
  p.threads = threads;
  for (int32_t i = 0; i < s.count(); i += 97) s.set_fixed(i, true);
  for (auto _ : state) {
    step(model, s, p);
    benchmark::DoNotOptimize(s.x.data());
  }
  state.SetItemsProcessed(state.iterations());  // items/s = iterations/s
  state.counters["particles"] = model.particle_count();
  state.counters["springs"] = static_cast<double>(springs);
  state.counters["threads"] = threads;
}

void BM_ImplicitBlock(benchmark::State& state) {
  const auto& m = block_model(state.range(0));
  run(state, m, static_cast<int>(state.range(1)), m.spring_count());
}
void BM_ExplicitBlock(benchmark::State& state) {
  const auto& g = block_model(state.range(0));
  static std::map<int64_t, std::unique_ptr<ExplicitSpringModel>> models;
  auto& e = models[state.range(0)];
  if (!e) e = std::make_unique<ExplicitSpringModel>(explicit_model_from_grid(g));
  run(state, *e, static_cast<int>(state.range(1)), e->spring_count());
}
void BM_ImplicitHeart2_4mm(benchmark::State& state) {
  run(state, heart_model(), static_cast<int>(state.range(0)), heart_model().spring_count());
}
void BM_ExplicitHeart2_4mm(benchmark::State& state) {
  static const ExplicitSpringModel e = explicit_model_from_grid(heart_model());
  run(state, e, static_cast<int>(state.range(0)), e.spring_count());
}

void block_args(benchmark::internal::Benchmark* b) {
  for (int64_t n : {10000, 20000, 40000, 50000, 100000})
    for (int t : {1, 2}) b->Args({n, t});
}
BENCHMARK(BM_ImplicitBlock)->Apply(block_args)->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK(BM_ExplicitBlock)->Apply(block_args)->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK(BM_ImplicitHeart2_4mm)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK(BM_ExplicitHeart2_4mm)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
