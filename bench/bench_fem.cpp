// Tetrahedral FEM (sim/fem_*.h) timings.
//
// 1. Static solves at the vertex counts of Huang et al.'s Table 2 (1,018 .. 5,071 vertices; their GPU
//    CG: 34-62 ms solve time, 219-1,297 ms average per deformation): a cube of n^3 cells (Kuhn tets,
//    (n+1)^3 vertices, n = 9, 12, 14, 16), 20 mm, neo-Hookean E = 30 kPa, nu = 0.45, bottom face fixed,
//    the centre of the top face grabbed 2 mm down (Newton, load factor 1, line search), and the
//    linear material under the same grab (one Newton step); diagonal and incomplete-Cholesky
//    preconditioned CG. Counters: Newton iterations, mean CG iterations per Newton step, ms per Newton
//    iteration, assembly and CG ms.
// 2. Explicit dynamics: element updates per second (tets x steps / s) of the full step (element pass,
//    node gather, central-difference update) at 10k .. 500k tets, 1 and 2 threads.
#include "ctsurg/sim/fem_box_mesh.h"
#include "ctsurg/sim/fem_explicit_dynamics.h"
#include "ctsurg/sim/fem_static_solver.h"

#include <benchmark/benchmark.h>

#include <cmath>
#include <map>
#include <memory>

namespace {

using namespace ctsurg::sim;

FemMaterial material(FemMaterialModel model) {
  FemMaterial m;
  m.model = model;
  m.youngs_modulus = 3e4;
  m.poisson_ratio = 0.45;
  return m;
}

const FemModel& cube(int n, FemMaterialModel model) {
  static std::map<std::pair<int, int>, std::unique_ptr<FemModel>> models;
  auto& slot = models[{n, static_cast<int>(model)}];
  if (!slot) {
    const auto box = fem_box_mesh({n, n, n}, {20, 20, 20});
    slot = std::make_unique<FemModel>(build_fem_model(box.nodes, box.tets, material(model)));
  }
  return *slot;
}

void static_solve(benchmark::State& state, FemMaterialModel model) {
  const int n = static_cast<int>(state.range(0));
  const auto pre = state.range(1) ? FemPreconditioner::incomplete_cholesky : FemPreconditioner::diagonal;
  const FemModel& m = cube(n, model);
  FemBoundaryConditions bc;
  for (int32_t i = 0; i < m.node_count(); ++i) {
    const double* p = &m.nodes[3 * i];
    if (p[2] == 0) bc.fixed_nodes.push_back(i);
    if (std::abs(p[2] - 20) < 1e-9 && std::hypot(p[0] - 10, p[1] - 10) <= 3.5) {
      bc.prescribed_nodes.push_back(i);
      bc.prescribed_displacements.insert(bc.prescribed_displacements.end(), {0.0, 0.0, -2.0});
    }
  }
  FemStaticOptions o;
  o.preconditioner = pre;
  FemStaticReport rep;
  for (auto _ : state) {
    rep = solve_fem_static(m, bc, {}, o).report;
    benchmark::DoNotOptimize(rep.relative_residual);
  }
  double cg = 0;
  for (int c : rep.cg_iterations) cg += c;
  state.counters["vertices"] = m.node_count();
  state.counters["tets"] = m.tet_count();
  state.counters["newton_its"] = rep.newton_iterations;
  state.counters["cg_its_per_newton"] = cg / std::max(1, rep.newton_iterations);
  state.counters["ms_per_newton"] = 1e3 * rep.seconds / std::max(1, rep.newton_iterations);
  state.counters["assembly_ms"] = 1e3 * rep.assembly_seconds;
  state.counters["cg_ms"] = 1e3 * rep.solve_seconds;
}

void BM_FemStaticNeoHookean(benchmark::State& s) { static_solve(s, FemMaterialModel::neo_hookean); }
void BM_FemStaticLinear(benchmark::State& s) { static_solve(s, FemMaterialModel::linear); }
BENCHMARK(BM_FemStaticNeoHookean)->ArgsProduct({{9, 12, 14, 16}, {0, 1}})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_FemStaticLinear)->ArgsProduct({{9, 12, 14, 16}, {0, 1}})->Unit(benchmark::kMillisecond)->UseRealTime();

// Explicit steps: a box of about `tets` tets (n x n x 2n cells, 12 n^3 tets), the bottom fixed, gravity,
// damping; a grab on top so that the body deforms.
void BM_FemExplicitStep(benchmark::State& state) {
  static const std::map<int64_t, int> sizes{{10000, 9}, {50000, 16}, {100000, 20}, {500000, 35}};
  const int n = sizes.at(state.range(0));
  const int threads = static_cast<int>(state.range(1));
  static std::map<int, std::unique_ptr<FemModel>> models;
  auto& slot = models[n];
  if (!slot) {
    const auto box = fem_box_mesh({n, n, 2 * n}, {20, 20, 40});
    slot = std::make_unique<FemModel>(build_fem_model(box.nodes, box.tets, material(FemMaterialModel::neo_hookean)));
  }
  const FemModel& m = *slot;
  FemDynamicsOptions o;
  o.threads = threads;
  o.gravity = {0, 0, -9810};
  o.mass_damping = 50;
  FemExplicitDynamics d(m, o);
  std::vector<int32_t> fixed;
  for (int32_t i = 0; i < m.node_count(); ++i)
    if (m.nodes[3 * i + 2] == 0) fixed.push_back(i);
  d.set_fixed_nodes(fixed);
  const int steps = 10;
  for (auto _ : state) d.step(steps);
  state.counters["tets"] = m.tet_count();
  state.counters["element_updates_per_s"] =
      benchmark::Counter(static_cast<double>(m.tet_count()) * steps, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_FemExplicitStep)
    ->ArgsProduct({{10000, 50000, 100000, 500000}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
