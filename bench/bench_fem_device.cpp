// The FEM on a CUDA device (docs/gpu.md; bench/gpu/run.sh turns the JSON into a table).
//
// 1. Explicit steps (FemExplicitDynamics, Backend::cuda): element updates per second (tets x steps / s)
//    at 10k, 100k, 500k and 2M tets: a box of n x n x 2n cells, 20 x 20 x 40 mm (12 n^3 Kuhn tets,
//    n = 9, 20, 35, 55), Neo-Hookean E = 30 kPa, nu = 0.45, bottom fixed, gravity, mass damping 50/s,
//    as bench_fem.cpp's BM_FemExplicitStep on the CPU. Steps run in calls of kBatch = 480 (30 chunks
//    of the default 16-step energy check: graph replays, one wait per call).
//    Effective bandwidth: the bytes one step must move per element if every array is read once and
//    nodes' displacements come from cache. Element pass: 4 node ids (16), B (36) and V (4) read, 12
//    corner forces (48) written; node pass, per node: CSR offset (4), 24 (element, corner) entries (96)
//    and their corner forces (288) read, u, u(t - dt), inverse mass (28) read, u(t + dt) (12) written:
//    428 B per node, 71 B per element (a Kuhn mesh has ~6 tets per node); u gathered by the element
//    pass, 12 B per node: 2 B per element. kBytesPerElement = 16 + 36 + 4 + 48 + 71 + 2 = 177 B.
// 2. Static solves (solve_fem_static) at the FEM paper's sizes (Huang et al., Table 2: 1,018 .. 5,071
//    vertices), as bench_fem.cpp's static_solve: a 20 mm cube of n^3 cells (n = 9, 12, 14, 16), linear
//    material, E = 30 kPa, nu = 0.45, bottom fixed, the top centre grabbed 2 mm down, Jacobi CG, on the
//    cpu (arg 0) and cuda (arg 1) backends: ms per solve, Newton and CG iterations, CG ms (on cuda
//    including the upload of the matrix values), assembly ms (host).
//
// Without a CUDA device (or in a build without CUDA) the program says so and exits 0.
#include "ctsurg/sim/base/backend.h"
#include "ctsurg/sim/fem/fem_box_mesh.h"
#include "ctsurg/sim/fem/fem_explicit_dynamics.h"
#include "ctsurg/sim/fem/fem_static_solver.h"
#include "ctsurg/sim/springs/device_simulation.h"

#include "device_bench_main.h"
#include "fem_bench_models.h"

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <memory>

namespace {

using namespace ctsurg::sim;

constexpr double kBytesPerElement = 177;
constexpr int kBatch = 480;  // steps per timed call

using bench::material;

double peak_gbs() {
  static const double peak = cuda_device_info(0).peak_bandwidth_gbs;
  return peak;
}

// A box of about `tets` tets (n x n x 2n cells).
const FemModel& column(int64_t tets) {
  static const std::map<int64_t, int> cells{{10000, 9}, {100000, 20}, {500000, 35}, {2000000, 55}};
  static std::map<int64_t, std::unique_ptr<FemModel>> models;
  auto& slot = models[tets];
  if (!slot) {
    const int n = cells.at(tets);
    const auto box = fem_box_mesh({n, n, 2 * n}, {20, 20, 40});
    slot = std::make_unique<FemModel>(build_fem_model(box.nodes, box.tets, material(FemLaw::neo_hookean)));
  }
  return *slot;
}

void BM_DeviceFemExplicitStep(benchmark::State& state) {
  const FemModel& m = column(state.range(0));
  FemDynamicsOptions o;
  o.gravity = {0, 0, -9810};
  o.mass_damping = 50;
  FemExplicitDynamics d(m, o, Backend::cuda);
  std::vector<int32_t> fixed;
  for (int32_t i = 0; i < m.node_count(); ++i)
    if (m.nodes[3 * i + 2] == 0) fixed.push_back(i);
  d.set_fixed_nodes(fixed);
  d.step(kBatch);  // warm-up: graph recording, caches
  for (auto _ : state) d.step(kBatch);
  const double tets = m.tet_count();
  const double steps = static_cast<double>(state.iterations()) * kBatch;
  state.SetItemsProcessed(static_cast<int64_t>(steps));  // items_per_second = steps per second
  state.counters["tets"] = tets;
  state.counters["element_updates/s"] = benchmark::Counter(tets * steps, benchmark::Counter::kIsRate);
  state.counters["bytes_per_element"] = kBytesPerElement;
  state.counters["GB/s"] = benchmark::Counter(kBytesPerElement * tets * steps / 1e9, benchmark::Counter::kIsRate);
  state.counters["peak_GB/s"] = peak_gbs();
}
BENCHMARK(BM_DeviceFemExplicitStep)
    ->Arg(10000)->Arg(100000)->Arg(500000)->Arg(2000000)
    ->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_FemStaticLinearCg(benchmark::State& state) {
  const FemModel& m = bench::cube(static_cast<int>(state.range(0)), FemLaw::linear);
  const Backend backend = state.range(1) ? Backend::cuda : Backend::cpu;
  const FemBoundaryConditions bc = bench::cube_grab(m, 2.0);
  FemStaticReport rep;
  for (auto _ : state) {
    rep = solve_fem_static(m, bc, {}, {}, backend).report;
    benchmark::DoNotOptimize(rep.relative_residual);
  }
  double cg = 0;
  for (int c : rep.cg_iterations) cg += c;
  state.SetLabel(backend_name(backend));
  state.counters["vertices"] = m.node_count();
  state.counters["tets"] = m.tet_count();
  state.counters["newton_its"] = rep.newton_iterations;
  state.counters["cg_its"] = cg;
  state.counters["cg_ms"] = 1e3 * rep.solve_seconds;
  state.counters["assembly_ms"] = 1e3 * rep.assembly_seconds;
}
BENCHMARK(BM_FemStaticLinearCg)->ArgsProduct({{9, 12, 14, 16}, {0, 1}})->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

int main(int argc, char** argv) { return ctsurg::sim::bench::run_device_benchmarks("bench_fem_device", argc, argv); }
