// Rigid instruments (sim/base/instrument.h, sim/springs/instrument_contact.h): what one costs.
//   BM_Bake            loading a bundled instrument: its signed distance grid, once per run
//   BM_HeartStep       one step of the bundled heart's 2.4 mm spring grid (48,789 particles) with no tool,
//                      with the sphere probe (5 mm) and with the instrument meshes pressed into its wall:
//                      the step's time with each tool, the contact's cost being the difference
//   BM_PushOut         the contact pass alone over N particles spread through the instrument's box
// bench/run.sh instruments writes the table in docs/benchmarks.md.
#include "ctsurg/sim/base/instrument.h"
#include "ctsurg/sim/springs/instrument_contact.h"
#include "ctsurg/sim/springs/sphere_tools.h"
#include "ctsurg/sim/springs/spring_grid_model.h"
#include "ctsurg/sim/springs/spring_mass_step.h"
#include "ctsurg/sim/springs/stability.h"
#include "heart_spring_model.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <filesystem>
#include <random>

namespace {

using namespace ctsurg::sim;

const std::filesystem::path kSource(CTSURG_SOURCE_DIR);
const char* const kInstruments[] = {"probe_rod.stl", "retractor_blade.obj", "forceps_jaw.ply", "scalpel.stl"};

const Instrument& instrument(int64_t k) {
  static std::vector<std::shared_ptr<const Instrument>> loaded;
  if (loaded.empty()) {
    for (const char* name : kInstruments) loaded.push_back(load_instrument(kSource / "data_samples" / "instruments" / name));
  }
  return *loaded[static_cast<size_t>(k)];
}

void BM_Bake(benchmark::State& state) {
  const auto path = kSource / "data_samples" / "instruments" / kInstruments[state.range(0)];
  std::shared_ptr<const Instrument> ins;
  for (auto _ : state) ins = load_instrument(path);
  state.SetLabel(kInstruments[state.range(0)]);
  state.counters["faces"] = static_cast<double>(ins->mesh.faces.size() / 3);
  state.counters["grid_nodes"] = static_cast<double>(ins->distance.phi.size());
  state.counters["spacing_mm"] = ins->distance.spacing;
}

const SpringGridModel& heart_model() { return ctsurg::bench::heart_spring_model(); }

// Tool 0: none; 1: the 5 mm sphere probe; 2 + k: instrument k. Each has its tip 3 mm behind the heart's
// anterior surface at the middle of its x and z extent (the anterior-most particle near there), unturned
// (shaft superior, broad faces anterior and posterior): pressed into the wall. The sphere's centre is
// 2 mm in front of that point (3 mm of it in the tissue). The state is pushed out once before timing.
void BM_HeartStep(benchmark::State& state) {
  const SpringGridModel& model = heart_model();
  ParticleState s = model.make_state();
  StepParameters p;
  p.dt = critical_time_step(model).dt * 0.5;
  p.damping = 0.01;
  p.threads = static_cast<int>(state.range(1));
  double lo[3] = {1e30, 1e30, 1e30}, hi[3] = {-1e30, -1e30, -1e30};
  for (int32_t i = 0; i < s.count(); ++i) {
    const double q[3] = {s.x[static_cast<size_t>(i)], s.y[static_cast<size_t>(i)], s.z[static_cast<size_t>(i)]};
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], q[a]), hi[a] = std::max(hi[a], q[a]);
  }
  double front = 1e30;  // the anterior-most (lowest y) particle within 5 mm of the middle of x and z
  const double mx = 0.5 * (lo[0] + hi[0]), mz = 0.5 * (lo[2] + hi[2]);
  for (int32_t i = 0; i < s.count(); ++i) {
    if (std::abs(s.x[static_cast<size_t>(i)] - mx) < 5 && std::abs(s.z[static_cast<size_t>(i)] - mz) < 5) {
      front = std::min(front, double(s.y[static_cast<size_t>(i)]));
    }
  }
  const std::array<double, 3> tip{mx, front + 3, mz};
  const int64_t tool = state.range(0);
  InstrumentView view;
  if (tool >= 2) view = instrument_view(instrument(tool - 2), kIdentityRotation, tip);
  const Sphere sphere{{tip[0], tip[1] - 2, tip[2]}, 5};
  const auto contact = [&] {
    if (tool == 1) return probe_sphere(s, sphere, p.threads);
    if (tool >= 2) return push_out_of_instrument(s, view, p.threads);
    return int64_t{0};
  };
  const int64_t in_contact = contact();
  for (auto _ : state) {
    step(model, s, p);
    benchmark::DoNotOptimize(contact());
  }
  state.SetLabel(tool == 0 ? "no tool" : tool == 1 ? "sphere probe 5 mm" : kInstruments[tool - 2]);
  state.SetItemsProcessed(state.iterations());
  state.counters["particles"] = s.count();
  state.counters["in_contact"] = static_cast<double>(in_contact);
  state.counters["threads"] = static_cast<double>(p.threads);
}

void BM_PushOut(benchmark::State& state) {
  const Instrument& ins = instrument(1);  // the retractor blade
  const auto& g = ins.distance;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  const int64_t n = state.range(0);
  std::vector<float> pos(static_cast<size_t>(3 * n)), mass(static_cast<size_t>(n), 1.0f);
  for (int64_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) pos[static_cast<size_t>(3 * i + a)] = static_cast<float>(g.origin[a] + u(rng) * g.spacing * (g.dims[a] - 1));
  const ParticleState original(pos, mass);
  ParticleState s = original;
  const InstrumentView v = instrument_view(ins, kIdentityRotation, {0, 0, 0});
  int64_t moved = 0;
  for (auto _ : state) {
    state.PauseTiming();
    s.x = original.x, s.y = original.y, s.z = original.z;
    state.ResumeTiming();
    moved = push_out_of_instrument(s, v, static_cast<int>(state.range(1)));
  }
  state.SetItemsProcessed(state.iterations() * n);
  state.counters["moved"] = static_cast<double>(moved);
  state.counters["threads"] = static_cast<double>(state.range(1));
}

BENCHMARK(BM_Bake)->DenseRange(0, 3)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_HeartStep)->ArgsProduct({{0, 1, 2, 3, 4, 5}, {1, 2}})->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK(BM_PushOut)->ArgsProduct({{10000, 100000, 1000000}, {1, 2}})->Unit(benchmark::kMicrosecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
