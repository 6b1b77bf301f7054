// Tetrahedral FEM (sim/fem_*.h) timings.
//
// 1. Static solves at the vertex counts of Huang et al.'s Table 2 (1,018 .. 5,071 vertices; their GPU
//    CG: 34-62 ms solve time, 219-1,297 ms average per deformation): a cube of n^3 cells (Kuhn tets,
//    (n+1)^3 vertices, n = 9, 12, 14, 16), 20 mm, neo-Hookean E = 30 kPa, nu = 0.45, bottom face fixed,
//    the centre of the top face grabbed 2 mm down (Newton, load factor 1, line search), and the
//    linear material under the same grab (one Newton step); diagonal and incomplete-Cholesky
//    preconditioned CG. Counters: Newton iterations, mean CG iterations per Newton step, ms per Newton
//    iteration, assembly and CG ms. And the linear material's factorised solver
//    (fem_linear_static_solver.h) for repeated solves: time per solve once the factor exists.
// 3. The cantilever of tests/sim/test_fem_static_solver.cpp at finer meshes than the test can afford
//    (n = 8, 12, 14 cells across the thickness, L = 10 h): counter error_pct = tip deflection error
//    against Euler-Bernoulli (linear tets lock in bending: the error falls as n^-2).
// 4. Issue 16: Neo-Hookean quasi-static frames on the direct (CHOLMOD) Newton path, linear and
//    quadratic tets (setup apart from the time per frame), and implicit Euler steps.
// 2. Explicit dynamics: element updates per second (tets x steps / s) of the full step (element pass,
//    node gather, central-difference update) at 10k .. 500k tets, 1 and 2 threads.
#include "ctsurg/sim/fem/fem_box_mesh.h"
#include "ctsurg/sim/fem/fem_explicit_dynamics.h"
#include "ctsurg/sim/fem/fem_implicit_dynamics.h"
#include "ctsurg/sim/fem/fem_linear_static_solver.h"
#include "ctsurg/sim/fem/fem_static_solver.h"

#include "ctsurg/sim/fem/fem_grip.h"
#include "fem_bench_models.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>

namespace {

using namespace ctsurg::sim;

using bench::cube;
using bench::cube_grab;
using bench::material;

void static_solve(benchmark::State& state, FemLaw model) {
  const int n = static_cast<int>(state.range(0));
  const auto pre = state.range(1) ? FemPreconditioner::incomplete_cholesky : FemPreconditioner::diagonal;
  const FemModel& m = cube(n, model);
  const FemBoundaryConditions bc = cube_grab(m, 2.0);
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

// The linear material's repeated solve (fem_linear_static_solver.h): the stiffness factorised once,
// then one condensed solve per frame as the grab moves (depths 2.0, 1.9, 1.8, ... mm: a different
// right-hand side every time). Counters: factor_ms (assembly + AMD + LDL^T, once), columns_ms (the
// grabbed nodes' unit responses, once per grab), the relative residual each solve reaches, and
// max_diff_mm against the Newton-CG solve of the same grab (CG tolerance 1e-12).
void BM_FemStaticLinearFactorised(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const FemModel& m = cube(n, FemLaw::linear);
  const FemBoundaryConditions bc = cube_grab(m, 2.0);
  FemBoundaryConditions supports;
  supports.fixed_nodes = bc.fixed_nodes;
  FemLinearStaticSolver solver(m, supports);
  std::vector<double> d = bc.prescribed_displacements;
  const FemStaticResult first = solver.solve(bc.prescribed_nodes, d, {});
  const double columns_ms = 1e3 * first.report.seconds;
  FemStaticOptions o;
  o.cg_tolerance = 1e-12;
  const FemStaticResult cg = solve_fem_static(m, bc, {}, o);
  double max_diff = 0;
  for (std::size_t i = 0; i < cg.displacements.size(); ++i) max_diff = std::max(max_diff, std::abs(cg.displacements[i] - first.displacements[i]));
  int k = 0;
  double worst_residual = first.report.relative_residual;
  for (auto _ : state) {
    const double depth = 2.0 - 0.1 * (k++ % 10);
    for (std::size_t g = 0; g < bc.prescribed_nodes.size(); ++g) d[3 * g + 2] = -depth;
    const FemStaticResult r = solver.solve(bc.prescribed_nodes, d, {});
    worst_residual = std::max(worst_residual, r.report.relative_residual);
    benchmark::DoNotOptimize(r.displacements.data());
  }
  state.counters["vertices"] = m.node_count();
  state.counters["tets"] = m.tet_count();
  state.counters["factor_ms"] = 1e3 * solver.stats().factor_seconds;
  state.counters["factor_nnz"] = static_cast<double>(solver.stats().factor_nonzeros);
  state.counters["columns_ms"] = columns_ms;
  state.counters["rel_residual"] = worst_residual;
  state.counters["max_diff_mm"] = max_diff;
}
BENCHMARK(BM_FemStaticLinearFactorised)->Arg(9)->Arg(12)->Arg(14)->Arg(16)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_FemStaticNeoHookean(benchmark::State& s) { static_solve(s, FemLaw::neo_hookean); }
void BM_FemStaticLinear(benchmark::State& s) { static_solve(s, FemLaw::linear); }
BENCHMARK(BM_FemStaticNeoHookean)->ArgsProduct({{9, 12, 14, 16}, {0, 1}})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_FemStaticLinear)->ArgsProduct({{9, 12, 14, 16}, {0, 1}})->Unit(benchmark::kMillisecond)->UseRealTime();

// Issue 16: the direct (CHOLMOD) Newton path at the Table 2 sizes, for the linear (4-node) and the
// quadratic (10-node) tets of the same cube. A FemStaticSolver kept across solves, as a scenario
// keeps it: setup_ms = the first solve of the 10 % grab (2 mm) from rest (pattern, analysis, the
// first factorisations), then each iteration is one quasi-static frame: the grab 0.1 mm further
// (2.0, 2.1, ... 2.9, 2.0, ... mm), warm-started from the previous frame. Counters: Newton
// iterations and factorisations per frame, the factor's size. range(1): tolerance in um (0: the
// relative 1e-8 rule); range(2): 1 linear tets, 2 quadratic; range(3): 0 Newton, 1 quasi-Newton (L-BFGS
// on the rest stiffness's factor, issue 32; counter quasi_newton_per_frame).
void BM_FemNeoHookeanGrabDirect(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const double tol_mm = 1e-3 * static_cast<double>(state.range(1));
  const bool quadratic = state.range(2) == 2;
  const bool quasi = state.range(3) == 1;
  const FemModel& lin = cube(n, FemLaw::neo_hookean);
  static std::map<int, std::unique_ptr<FemModel>> quadratic_models;
  auto& q = quadratic_models[n];
  if (quadratic && !q) {
    const auto box = fem_box_mesh({n, n, n}, {20, 20, 20});
    q = std::make_unique<FemModel>(build_quadratic_fem_model(box.nodes, box.tets, material(FemLaw::neo_hookean)));
  }
  const FemModel& m = quadratic ? *q : lin;
  FemBoundaryConditions bc = cube_grab(m, 2.0);
  FemStaticOptions o;
  o.linear_solve = FemLinearSolve::direct;
  o.tolerance_mm = tol_mm;
  if (quasi) o.nonlinear = FemNonlinearSolve::quasi_newton;
  FemStaticSolver solver(m, o);
  const FemStaticResult first = solver.solve(bc, {});
  std::vector<double> u = first.displacements;
  int k = 0, frames = 0, newton = 0, factorizations = 0, lbfgs = 0;
  double solve_s = 0, assembly_s = 0;
  for (auto _ : state) {
    const double depth = 2.0 + 0.1 * (++k % 10);
    for (std::size_t g = 0; g < bc.prescribed_nodes.size(); ++g) bc.prescribed_displacements[3 * g + 2] = -depth;
    const FemStaticResult r = solver.solve(bc, {}, &u);
    u = r.displacements;
    ++frames;
    newton += r.report.newton_iterations;
    lbfgs += r.report.quasi_newton_iterations;
    factorizations += r.report.factorizations;
    solve_s += r.report.solve_seconds;
    assembly_s += r.report.assembly_seconds;
  }
  // Of a frame: the linear solves (factorisations, substitutions, the two-loop recursion) and the tangent's assembly, ms.
  state.counters["solve_ms"] = 1e3 * solve_s / std::max(1, frames);
  state.counters["assembly_ms"] = 1e3 * assembly_s / std::max(1, frames);
  state.counters["quasi_newton_per_frame"] = static_cast<double>(lbfgs) / std::max(1, frames);
  state.counters["vertices"] = lin.node_count();
  state.counters["nodes"] = m.node_count();
  state.counters["setup_ms"] = 1e3 * first.report.seconds;
  state.counters["setup_newton"] = first.report.newton_iterations;
  state.counters["newton_per_frame"] = static_cast<double>(newton) / std::max(1, frames);
  state.counters["factorizations_per_frame"] = static_cast<double>(factorizations) / std::max(1, frames);
  state.counters["factor_mb"] = static_cast<double>(first.report.factor_bytes) / 1048576.0;
}
BENCHMARK(BM_FemNeoHookeanGrabDirect)
    ->ArgsProduct({{9, 12, 14, 16}, {0, 10}, {1}, {0}})
    ->ArgsProduct({{9, 12, 14, 16}, {10}, {1}, {1}})
    ->Args({9, 10, 2, 0})
    ->Args({16, 10, 2, 0})
    ->Args({9, 10, 2, 1})
    ->Args({16, 10, 2, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Issue 16: one implicit step of 1/60 s per iteration, the grab moving 0.1 mm a step (as a live drag),
// at the Table 2 sizes; Neo-Hookean and corotational, tolerance 0.01 mm. range(2): 0 Newton, 1
// quasi-Newton; range(3): 0 backward Euler, 1 midpoint (issue 32). Counters: Newton (and L-BFGS)
// iterations and factorisations per step.
void BM_FemImplicitStep(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const auto law = state.range(1) ? FemLaw::corotational : FemLaw::neo_hookean;
  const FemModel& m = cube(n, law);
  FemBoundaryConditions bc = cube_grab(m, 0.0);
  FemImplicitOptions o;
  o.newton.tolerance_mm = 0.01;
  if (state.range(2) == 1) o.newton.nonlinear = FemNonlinearSolve::quasi_newton;
  if (state.range(3) == 1) o.scheme = FemImplicitScheme::midpoint;
  FemImplicitDynamics d(m, o);
  d.set_supports(bc.fixed_nodes);
  d.set_prescribed(bc.prescribed_nodes, bc.prescribed_displacements);
  d.step(1);  // the pattern, the analysis, the first factor
  int k = 0, steps = 0, newton = 0, factorizations = 0, lbfgs = 0;
  for (auto _ : state) {
    const double depth = 0.1 * (++k % 30);
    for (std::size_t g = 0; g < bc.prescribed_nodes.size(); ++g) bc.prescribed_displacements[3 * g + 2] = -depth;
    d.set_prescribed(bc.prescribed_nodes, bc.prescribed_displacements);
    const FemImplicitStepReport r = d.step(1);
    ++steps;
    newton += r.newton_iterations;
    lbfgs += r.quasi_newton_iterations;
    factorizations += r.factorizations;
  }
  state.counters["vertices"] = m.node_count();
  state.counters["newton_per_step"] = static_cast<double>(newton) / std::max(1, steps);
  state.counters["quasi_newton_per_step"] = static_cast<double>(lbfgs) / std::max(1, steps);
  state.counters["factorizations_per_step"] = static_cast<double>(factorizations) / std::max(1, steps);
}
BENCHMARK(BM_FemImplicitStep)
    ->ArgsProduct({{9, 12, 14, 16}, {0, 1}, {0}, {0}})
    ->ArgsProduct({{9, 12, 14, 16}, {0}, {1}, {0}})
    ->Args({16, 0, 0, 1})
    ->Unit(benchmark::kMillisecond)->UseRealTime();

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
    slot = std::make_unique<FemModel>(build_fem_model(box.nodes, box.tets, material(FemLaw::neo_hookean)));
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

// Cantilever L x h x h, L = 10 h, clamped at x = 0, a small tip load spread over the end face as a
// uniform shear traction (area / 3 per triangle corner); linear material, E 30 kPa, nu 0.3.
void BM_FemCantileverLinear(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const double h = 2.0, L = 10 * h, E = 3e4;
  const auto box = fem_box_mesh({10 * n, n, n}, {L, h, h});
  FemMaterial m;
  m.law = FemLaw::linear;
  m.youngs_modulus = E;
  m.poisson_ratio = 0.3;
  const FemModel model = build_fem_model(box.nodes, box.tets, m);
  const double I = h * h * h * h / 12, delta = 1e-3 * L, P = delta * 3 * E * I / (L * L * L);
  FemBoundaryConditions bc;
  std::vector<int32_t> tip;
  for (int32_t i = 0; i < model.node_count(); ++i) {
    if (std::abs(model.nodes[3 * i]) < 1e-9) bc.fixed_nodes.push_back(i);
    if (std::abs(model.nodes[3 * i] - L) < 1e-9) tip.push_back(i);
  }
  FemLoads loads;
  loads.forces.assign(model.nodes.size(), 0.0);
  static const int faces[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  const double traction = P / (h * h);
  for (int32_t e = 0; e < model.tet_count(); ++e) {
    for (const auto& fc : faces) {
      int32_t v[3];
      bool on = true;
      for (int k = 0; k < 3; ++k) {
        v[k] = model.tets[4 * e + fc[k]];
        on = on && std::abs(model.nodes[3 * v[k]] - L) < 1e-9;
      }
      if (!on) continue;
      const double* a = &model.nodes[3 * v[0]];
      const double* b = &model.nodes[3 * v[1]];
      const double* c = &model.nodes[3 * v[2]];
      const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
      const double area = 0.5 * std::sqrt(std::pow(u[1] * w[2] - u[2] * w[1], 2) + std::pow(u[2] * w[0] - u[0] * w[2], 2) +
                                          std::pow(u[0] * w[1] - u[1] * w[0], 2));
      for (int k = 0; k < 3; ++k) loads.forces[3 * v[k] + 2] += traction * area / 3;
    }
  }
  FemStaticOptions o;
  o.preconditioner = FemPreconditioner::incomplete_cholesky;
  double err = 0;
  int cg = 0;
  for (auto _ : state) {
    const auto r = solve_fem_static(model, bc, loads, o);
    double wsum = 0;
    for (const int32_t i : tip) wsum += r.displacements[3 * i + 2] / static_cast<double>(tip.size());
    err = (wsum - delta) / delta;
    cg = r.report.cg_iterations.empty() ? 0 : r.report.cg_iterations[0];
  }
  state.counters["tets"] = model.tet_count();
  state.counters["error_pct"] = 100 * err;
  state.counters["cg_iterations"] = cg;
}
BENCHMARK(BM_FemCantileverLinear)->Arg(8)->Arg(12)->Arg(14)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

// A volume grip's capture (fem_grip.h): the integral of the penalty over the elements near an 8 mm sphere
// at the centre of a 96 mm cube of 16^3 cells (6 mm cells: the live heart's tet size; 4,913 vertices), on
// linear and on quadratic tets (arg 1: order). What a grab's begin costs before its first frame.
void BM_FemGripCapture(benchmark::State& state) {
  static const auto box = fem_box_mesh({16, 16, 16}, {96, 96, 96});
  static const FemModel p1 = build_fem_model(box.nodes, box.tets, material(FemLaw::neo_hookean));
  static const FemModel p2 = build_quadratic_fem_model(box.nodes, box.tets, material(FemLaw::neo_hookean));
  const FemModel& m = state.range(0) == 2 ? p2 : p1;
  const std::vector<double> u(3 * static_cast<size_t>(m.node_count()), 0.0);
  FemGrip g;
  for (auto _ : state) {
    g = fem_capture_grip(m, u, {47, 49, 50}, 8, 2, 1.0);
    benchmark::DoNotOptimize(g.matrices.data());
  }
  state.counters["elements"] = static_cast<double>(g.elements.size());
  state.counters["volume_mm3"] = g.volume_mm3;
}
BENCHMARK(BM_FemGripCapture)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK_MAIN();
