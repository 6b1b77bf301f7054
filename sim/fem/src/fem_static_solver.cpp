#include "ctsurg/sim/fem/fem_static_solver.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/elapsed_seconds.h"
#include "device_conjugate_gradient.h"
#include "fem_newton.h"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <chrono>
#include <sstream>
#include <string>

namespace ctsurg::sim {
namespace {

constexpr const char* kStaticWhere = "fem static";
using Clock = std::chrono::steady_clock;

}  // namespace

FemStaticSolver::FemStaticSolver(const FemModel& model, const FemStaticOptions& options, Backend backend)
    : model_(model), options_(options) {
  if (!backend_available(backend)) require_backend(backend, kStaticWhere);  // cuda without a CUDA build or device: says why
  validate_fem_static(model, {}, {}, options);
  if (backend == Backend::cuda) {
    if (options.preconditioner != FemPreconditioner::diagonal)
      throw InputError(kStaticWhere, "preconditioner",
                       "the cuda backend's conjugate gradient is diagonal (Jacobi) preconditioned; use diagonal, or "
                       "incomplete_cholesky on the cpu backend");
    device_cg_ = std::make_unique<DeviceConjugateGradient>(kStaticWhere);
  }
  newton_ = std::make_unique<FemNewton>(model, options, device_cg_.get(), kStaticWhere);
}

FemStaticSolver::~FemStaticSolver() = default;

FemStaticResult FemStaticSolver::solve(const FemBoundaryConditions& bc, const FemLoads& loads, const std::vector<double>* initial) {
  FemStaticOptions checked = options_;
  if (initial != nullptr) checked.initial_displacements = *initial;
  validate_fem_static(model_, bc, loads, checked);
  const std::vector<double>& start = initial != nullptr ? *initial : options_.initial_displacements;
  const auto t0 = Clock::now();
  const int32_t n = model_.node_count();
  const std::size_t n3 = 3 * static_cast<std::size_t>(n);
  std::vector<uint8_t> held(n3, 0);
  std::vector<double> target(n3, 0.0), external(n3, 0.0);
  for (int32_t i : bc.fixed_nodes) held[3 * i] = held[3 * i + 1] = held[3 * i + 2] = 1;
  for (int32_t c : bc.fixed_components) held[c] = 1;
  for (std::size_t g = 0; g < bc.prescribed_nodes.size(); ++g)
    for (int a = 0; a < 3; ++a) {
      held[3 * bc.prescribed_nodes[g] + a] = 1;
      target[3 * bc.prescribed_nodes[g] + a] = bc.prescribed_displacements[3 * g + a];
    }
  for (int32_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c)
      external[3 * i + c] = (loads.forces.empty() ? 0.0 : loads.forces[3 * i + c]) + model_.node_load[i] * loads.gravity[c];
  FemNewton& newton = *newton_;
  newton.set_grips(loads.grips);  // first: a grip holds the model as a support does (set_held's check)
  newton.set_held(held, target);
  newton.set_external(external);

  FemStaticResult result;
  FemStaticReport& rep = result.report;
  rep.reference_residual = newton.needs_reference() ? newton.reference_residual() : NAN;
  rep.free_components = newton.free_components();
  std::vector<double> u(n3, 0.0), trial;
  double factor = 0, increment = 1.0 / options_.load_steps;
  int halvings = 0;
  std::string last_failure;
  if (rep.reference_residual == 0) factor = 1;  // nothing to do: u = 0 is the solution
  if (factor < 1 && !start.empty()) {  // warm start: the full load at once
    trial = start;  // held components are lifted to their targets by newton()
    if (newton.newton(trial, 1.0, rep, last_failure)) {
      u.swap(trial);
      factor = 1;
      rep.load_factors.push_back(factor);
      ++rep.load_steps;
    } else {
      rep.warm_start_failed = true;
    }
  }
  while (factor < 1) {
    const double next = std::min(1.0, factor + increment);
    trial = u;  // held components at the last factor's values: Newton lifts them
    if (newton.newton(trial, next, rep, last_failure)) {
      u.swap(trial);
      factor = next;
      rep.load_factors.push_back(factor);
      ++rep.load_steps;
    } else {
      if (++halvings > options_.max_halvings) {
        std::ostringstream s;
        s << "fem static: the load increment from factor " << factor << " to " << next << " failed after " << options_.max_halvings
          << " halvings (" << last_failure << "); try smaller loads or more load_steps";
        throw RuntimeError(s.str());
      }
      ++rep.halvings;
      increment /= 2;
    }
  }
  std::vector<double> f;
  if (!newton.last_forces(u, 1.0, f)) newton.forces(u, 1.0, f);
  double r2 = 0;
  for (std::size_t d = 0; d < n3; ++d)
    if (!newton.held()[d]) r2 += f[d] * f[d];
  rep.relative_residual = std::isnan(rep.reference_residual) ? NAN : rep.reference_residual > 0 ? std::sqrt(r2) / rep.reference_residual : 0;
  rep.converged = true;
  rep.direct = newton.direct();
  rep.factor_bytes = newton.factor_bytes();
  result.reactions.assign(n3, 0.0);
  for (std::size_t d = 0; d < n3; ++d)
    if (newton.held()[d]) result.reactions[d] = -f[d];
  result.displacements = std::move(u);
  rep.seconds = seconds_since(t0);
  return result;
}

FemStaticResult solve_fem_static(const FemModel& model, const FemBoundaryConditions& bc, const FemLoads& loads,
                                 const FemStaticOptions& options, Backend backend) {
  FemStaticSolver solver(model, options, backend);
  return solver.solve(bc, loads);
}

}  // namespace ctsurg::sim
