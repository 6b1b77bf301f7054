// Why CHOLMOD (issue 16): the FEM's tangent stiffness factorised by Eigen's own sparse Cholesky
// (simplicial LLT and LDLT, AMD ordering) and by SuiteSparse's CHOLMOD (supernodal and simplicial,
// its default ordering: AMD or METIS by trial, through Eigen's CholmodSupport), on the linear
// material's stiffness of the Table 2 cubes (n = 9, 16, 24 cells a side: 1,000 .. 15,625 vertices,
// the bottom face fixed). Each iteration is one numeric factorisation (the analysis is done once,
// outside the loop, as FemNewton does per held set); counters: analysis ms, one solve (forward and
// back substitution) ms, the factor's non-zeros where the solver reports them. CHOLMOD's BLAS is the
// system's (OpenBLAS), one thread here. BM_SparseCholeskySolve (below): the substitutions alone, double
// against ctsurg's single-precision form.
#include "ctsurg/sim/fem/fem_box_mesh.h"
#include "ctsurg/sim/fem/fem_forces.h"
#include "ctsurg/sim/fem/fem_model.h"

#include "fem_bench_models.h"
#include "sparse_cholesky.h"

#include <Eigen/CholmodSupport>
#include <Eigen/SparseCholesky>
#include <benchmark/benchmark.h>
#include <dlfcn.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <vector>

namespace {

using namespace ctsurg::sim;
using SpMat = Eigen::SparseMatrix<double>;

// K on the free components (z > 0) of the linear material's cube of n^3 cells, built once per n.
const SpMat& stiffness(int n) {
  static std::map<int, std::unique_ptr<SpMat>> cache;
  auto& slot = cache[n];
  if (slot) return *slot;
  const FemModel& m = bench::cube(n, FemLaw::linear);
  std::vector<int> free(m.nodes.size(), -1);
  int count = 0;
  for (int32_t i = 0; i < m.node_count(); ++i)
    for (int a = 0; a < 3; ++a)
      if (m.nodes[3 * i + 2] > 1e-9) free[3 * i + a] = count++;
  const std::vector<double> u(m.nodes.size(), 0.0);
  std::vector<Eigen::Triplet<double>> t;
  for (int32_t e = 0; e < m.tet_count(); ++e) {
    const auto k = fem_element_stiffness(m, e, u);
    for (int r = 0; r < 12; ++r)
      for (int c = 0; c < 12; ++c) {
        const int gr = free[3 * m.tets[4 * e + r / 3] + r % 3], gc = free[3 * m.tets[4 * e + c / 3] + c % 3];
        if (gr >= 0 && gc >= 0) t.emplace_back(gr, gc, k[12 * r + c]);
      }
  }
  slot = std::make_unique<SpMat>(count, count);
  slot->setFromTriplets(t.begin(), t.end());
  return *slot;
}

// OpenBLAS on one thread, as the FEM's own factorisations run it (sim/fem/src/sparse_cholesky.cpp says
// why): with its default thread per core, CHOLMOD's supernodal solves wait on a second core and a
// loaded 2-core machine made them 100x slower. Looked up at run time, so that any BLAS links.
void one_blas_thread() {
  using SetThreads = void (*)(int);
  if (const auto set = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"))) set(1);
}

template <class Solver>
void factorise(benchmark::State& state) {
  one_blas_thread();
  const SpMat& K = stiffness(static_cast<int>(state.range(0)));
  Solver solver;
  const auto t0 = std::chrono::steady_clock::now();
  solver.analyzePattern(K);
  const double analyse = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (auto _ : state) {
    solver.factorize(K);
    if (solver.info() != Eigen::Success) state.SkipWithError("factorisation failed");
  }
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(K.rows());
  const auto t1 = std::chrono::steady_clock::now();
  const Eigen::VectorXd x = solver.solve(b);
  const double solve = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
  state.counters["unknowns"] = static_cast<double>(K.rows());
  state.counters["analyse_ms"] = 1e3 * analyse;
  state.counters["solve_ms"] = 1e3 * solve;
  state.counters["rel_residual"] = (K * x - b).norm() / b.norm();
}

using EigenLLT = Eigen::SimplicialLLT<SpMat, Eigen::Lower, Eigen::AMDOrdering<int>>;
using EigenLDLT = Eigen::SimplicialLDLT<SpMat, Eigen::Lower, Eigen::AMDOrdering<int>>;
using CholmodSupernodal = Eigen::CholmodSupernodalLLT<SpMat, Eigen::Lower>;
using CholmodSimplicial = Eigen::CholmodSimplicialLLT<SpMat, Eigen::Lower>;

void BM_EigenSimplicialLLT(benchmark::State& s) { factorise<EigenLLT>(s); }
void BM_EigenSimplicialLDLT(benchmark::State& s) { factorise<EigenLDLT>(s); }
void BM_CholmodSupernodalLLT(benchmark::State& s) { factorise<CholmodSupernodal>(s); }
void BM_CholmodSimplicialLLT(benchmark::State& s) { factorise<CholmodSimplicial>(s); }
BENCHMARK(BM_EigenSimplicialLLT)->Arg(9)->Arg(16)->Arg(24)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_EigenSimplicialLDLT)->Arg(9)->Arg(16)->Arg(24)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_CholmodSupernodalLLT)->Arg(9)->Arg(16)->Arg(24)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_CholmodSimplicialLLT)->Arg(9)->Arg(16)->Arg(24)->Unit(benchmark::kMillisecond)->UseRealTime();

// The substitutions alone (issue 32): one solve with ctsurg's SparseCholesky (sim/fem/src/sparse_cholesky.h)
// of the cube's K, range(1): 0 CHOLMOD's double-precision solve, 1 the single-precision form (its blocks
// [L_kk; L_bk] L_kk^-1: one matrix-vector product per supernode and substitution, two subtrees of the
// elimination tree at once), range(2) threads for it. What the quasi-Newton iteration pays per iteration
// for H_0 (fem_quasi_newton.cpp). Counters: the factor's MB (double), the single form's relative
// difference from the double solve.
void BM_SparseCholeskySolve(benchmark::State& state) {
  one_blas_thread();
  const SpMat& K = stiffness(static_cast<int>(state.range(0)));
  const bool single = state.range(1) == 1;
  const int threads = static_cast<int>(state.range(2));
  // Both triangles as compressed columns (= rows: K is symmetric), sorted, as FemNewton gives them.
  SpMat a = K;
  a.makeCompressed();
  ctsurg::sim::SparseCholesky chol("bench");
  chol.analyze(static_cast<int32_t>(a.rows()), a.outerIndexPtr(), a.innerIndexPtr());
  if (chol.factorize(a.valuePtr()) >= 0) {
    state.SkipWithError("not positive definite");
    return;
  }
  chol.make_single();
  std::vector<double> b(static_cast<size_t>(a.rows())), x(b.size()), x_double(b.size());
  for (size_t i = 0; i < b.size(); ++i) b[i] = std::cos(0.1 * static_cast<double>(i));
  for (auto _ : state) {
    if (single) {
      chol.solve_single(b.data(), x.data(), threads);
    } else {
      chol.solve(b.data(), x.data());
    }
    benchmark::DoNotOptimize(x.data());
  }
  chol.solve(b.data(), x_double.data());
  chol.solve_single(b.data(), x.data(), threads);
  double diff = 0, size = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    diff = std::max(diff, std::abs(x[i] - x_double[i]));
    size = std::max(size, std::abs(x_double[i]));
  }
  state.counters["unknowns"] = static_cast<double>(a.rows());
  state.counters["factor_mb"] = static_cast<double>(chol.factor_bytes()) / 1048576.0;
  state.counters["single_rel_diff"] = diff / size;
}
BENCHMARK(BM_SparseCholeskySolve)
    ->ArgsProduct({{9, 16, 24}, {0}, {1}})
    ->ArgsProduct({{9, 16, 24}, {1}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
