#include "ctsurg/sim/fem/fem_implicit_dynamics.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/fem/fem_forces.h"
#include "device_conjugate_gradient.h"
#include "fem_newton.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

namespace ctsurg::sim {
namespace {

constexpr const char* kImplicitWhere = "fem implicit";
using Clock = std::chrono::steady_clock;

}  // namespace

FemImplicitDynamics::FemImplicitDynamics(const FemModel& model, const FemImplicitOptions& options, Backend backend)
    : model_(model), options_(options) {
  if (!backend_available(backend)) require_backend(backend, kImplicitWhere);
  const auto& o = options;
  if (!(std::isfinite(o.dt) && o.dt > 0)) throw InputError(kImplicitWhere, "dt", "must be finite and > 0 s");
  if (!(std::isfinite(o.mass_damping) && o.mass_damping >= 0)) throw InputError(kImplicitWhere, "mass_damping", "must be finite and >= 0 (1/s)");
  if (!(std::isfinite(o.stiffness_damping) && o.stiffness_damping >= 0))
    throw InputError(kImplicitWhere, "stiffness_damping", "must be finite and >= 0 (s)");
  for (double g : o.gravity)
    if (!std::isfinite(g)) throw InputError(kImplicitWhere, "gravity", "must be finite");
  if (o.max_halvings < 0 || o.max_halvings > 20) throw InputError(kImplicitWhere, "max_halvings", "must be in [0, 20]");
  if (o.threads < 0) throw InputError(kImplicitWhere, "threads", "must be >= 0");
  if (options_.newton.tolerance_mm == 0) options_.newton.tolerance_mm = 1e-4;
  options_.newton.threads = o.threads;
  options_.newton.initial_displacements.clear();
  options_.newton.estimate_error = false;  // a step's FemAdvance carries no solver error
  validate_fem_static(model, {}, {}, options_.newton);
  if (backend == Backend::cuda) device_cg_ = std::make_unique<DeviceConjugateGradient>(kImplicitWhere);
  newton_ = std::make_unique<FemNewton>(model, options_.newton, device_cg_.get(), kImplicitWhere);
  const std::size_t n3 = 3 * static_cast<std::size_t>(model.node_count());
  fixed_.assign(3 * static_cast<std::size_t>(model.node_count()), 0);
  u_.assign(n3, 0.0);
  v_.assign(n3, 0.0);
  set_external_forces({});
}

FemImplicitDynamics::~FemImplicitDynamics() = default;

void FemImplicitDynamics::set_supports(const std::vector<int32_t>& nodes, const std::vector<int32_t>& components) {
  fixed_.assign(fixed_.size(), 0);
  for (const int32_t n : nodes) {
    if (n < 0 || n >= model_.node_count()) throw InputError(kImplicitWhere, "fixed_nodes", "node " + std::to_string(n) + " out of range");
    for (int a = 0; a < 3; ++a) fixed_[3 * static_cast<std::size_t>(n) + a] = 1;
  }
  for (const int32_t c : components) {
    if (c < 0 || c >= 3 * model_.node_count()) throw InputError(kImplicitWhere, "fixed_components", "component " + std::to_string(c) + " out of range");
    fixed_[static_cast<std::size_t>(c)] = 1;
  }
  for (std::size_t d = 0; d < fixed_.size(); ++d)
    if (fixed_[d]) u_[d] = v_[d] = 0;
}

void FemImplicitDynamics::set_prescribed(const std::vector<int32_t>& nodes, const std::vector<double>& displacements) {
  if (displacements.size() != 3 * nodes.size()) throw InputError(kImplicitWhere, "prescribed_displacements", "expected #G x 3 values");
  for (const int32_t n : nodes)
    if (n < 0 || n >= model_.node_count()) throw InputError(kImplicitWhere, "prescribed_nodes", "node " + std::to_string(n) + " out of range");
  for (const double d : displacements)
    if (!std::isfinite(d)) throw InputError(kImplicitWhere, "prescribed_displacements", "must be finite");
  prescribed_nodes_ = nodes;
  prescribed_ = displacements;
}

void FemImplicitDynamics::clear_prescribed() {
  prescribed_nodes_.clear();
  prescribed_.clear();
}

void FemImplicitDynamics::set_grips(std::vector<FemGrip> grips) {
  std::vector<std::vector<double>> start;
  for (const FemGrip& g : grips) {
    const FemGrip* before = nullptr;
    for (const FemGrip& o : grips_)
      if (o.elements == g.elements && o.nodes == g.nodes) before = &o;
    start.push_back(before != nullptr ? before->target : g.target);
  }
  grips_ = std::move(grips);
  grip_start_ = std::move(start);
}

void FemImplicitDynamics::set_external_forces(const std::vector<double>& forces) {
  const std::size_t n3 = 3 * static_cast<std::size_t>(model_.node_count());
  if (!forces.empty() && forces.size() != n3) throw InputError(kImplicitWhere, "forces", "expected #N x 3 values or none");
  for (const double f : forces)
    if (!std::isfinite(f)) throw InputError(kImplicitWhere, "forces", "must be finite");
  forces_ = forces;
  external_.assign(n3, 0.0);
  for (std::size_t d = 0; d < n3; ++d) external_[d] = (forces_.empty() ? 0.0 : forces_[d]) + model_.node_mass[d / 3] * options_.gravity[d % 3];
}

// One backward Euler step of length h from (u_, v_), the grab at `start` + fraction (its target -
// `start`) at its end (sub-steps move it in equal parts); on success the state moves on.
bool FemImplicitDynamics::advance(double h, const std::vector<double>& start, double fraction, FemImplicitStepReport& report,
                                  std::string& failure) {
  const std::size_t n3 = u_.size();
  std::vector<uint8_t> held(n3, 0);
  std::vector<double> target(n3, 0.0);
  for (std::size_t d = 0; d < fixed_.size(); ++d) held[d] = fixed_[d];
  for (std::size_t g = 0; g < prescribed_nodes_.size(); ++g)
    for (int a = 0; a < 3; ++a) {
      const std::size_t d = 3 * static_cast<std::size_t>(prescribed_nodes_[g]) + a;
      held[d] = 1;
      target[d] = fraction == 1 ? prescribed_[3 * g + a] : start[d] + fraction * (prescribed_[3 * g + a] - start[d]);
    }
  // The inertia and damping terms (fem_newton.h). Backward Euler, for u = u_{n+1}: c_m (u - y) =
  // (u - u_n - h v_n) / h^2 + alpha (u - u_n) / h. Midpoint, for u = w = (u_n + u_{n+1}) / 2: c_m (u - y) =
  // 4 (u - u_n - h v_n / 2) / h^2 + 2 alpha (u - u_n) / h; the held components' w halfway to their targets.
  const double alpha = options_.mass_damping, beta = options_.stiffness_damping;
  const bool midpoint = options_.scheme == FemImplicitScheme::midpoint;
  const double ci = midpoint ? 4 / (h * h) : 1 / (h * h), cv = midpoint ? 0.5 * h : h, ca = midpoint ? 2 * alpha / h : alpha / h;
  FemNewtonTerms terms;
  terms.mass = ci + ca;
  terms.inertia_target.resize(n3);
  for (std::size_t d = 0; d < n3; ++d) terms.inertia_target[d] = (ci * (u_[d] + cv * v_[d]) + ca * u_[d]) / terms.mass;
  terms.stiffness_damping = (midpoint ? 2 : 1) * beta / h;
  if (beta != 0) terms.damping_origin = u_;
  if (midpoint) {
    terms.gradient_origin = u_;  // the discrete gradient: the energy kept for every law (fem_newton.h)
    for (std::size_t d = 0; d < n3; ++d)
      if (held[d]) target[d] = 0.5 * (u_[d] + target[d]);
  }
  // The grips' targets at the sub-step's end (the midpoint scheme: at its middle).
  std::vector<FemGrip> grips = grips_;
  const double f0 = std::max(0.0, fraction - h / options_.dt);
  for (std::size_t g = 0; g < grips.size(); ++g)
    for (std::size_t k = 0; k < grips[g].target.size(); ++k) {
      const double a = grip_start_[g][k], b = grips_[g].target[k];
      const double end = a + fraction * (b - a);
      grips[g].target[k] = midpoint ? 0.5 * (a + f0 * (b - a) + end) : end;
    }
  FemNewton& newton = *newton_;
  newton.set_grips(grips);
  newton.set_terms(std::move(terms));  // first: with inertia, no support is needed (set_held)
  newton.set_held(held, target);
  newton.set_external(external_);
  FemStaticReport rep;
  rep.reference_residual = newton.needs_reference() ? newton.reference_residual() : NAN;
  std::vector<double> u(n3);
  for (std::size_t d = 0; d < n3; ++d) u[d] = held[d] ? u_[d] : u_[d] + cv * v_[d];  // the predictor; held ones are lifted
  const bool ok = newton.newton(u, 1.0, rep, failure);
  report.newton_iterations += rep.newton_iterations;
  report.quasi_newton_iterations += rep.quasi_newton_iterations;
  report.factorizations += rep.factorizations;
  if (!ok) return false;
  if (midpoint) {
    // u_{n+1} = 2 w - u_n, v_{n+1} = 2 (u_{n+1} - u_n) / h - v_n = 4 (w - u_n) / h - v_n; a held component's velocity is its mean over
    // the step (it does not enter the free components' equations).
    for (std::size_t d = 0; d < n3; ++d) {
      const double next = 2 * u[d] - u_[d];
      v_[d] = held[d] ? (next - u_[d]) / h : 2 * (next - u_[d]) / h - v_[d];
      u_[d] = next;
    }
    return true;
  }
  for (std::size_t d = 0; d < n3; ++d) {
    v_[d] = (u[d] - u_[d]) / h;
    u_[d] = u[d];
  }
  return true;
}

FemImplicitStepReport FemImplicitDynamics::step(int steps) {
  if (steps < 0) throw InputError(kImplicitWhere, "steps", "must be >= 0");
  const auto t0 = Clock::now();
  FemImplicitStepReport report;
  for (int k = 0; k < steps; ++k) {
    const std::vector<double> u0 = u_, v0 = v_;
    std::string failure;
    int sub = 1;
    while (true) {
      bool ok = true;
      for (int s = 0; s < sub && ok; ++s) ok = advance(options_.dt / sub, u0, static_cast<double>(s + 1) / sub, report, failure);
      if (ok) break;
      u_ = u0;
      v_ = v0;
      if (sub >= (1 << options_.max_halvings)) {
        throw RuntimeError(std::string(kImplicitWhere) + ": the step at t = " + std::to_string(time_) + " s failed in " + std::to_string(sub) +
                           " sub-steps of " + std::to_string(options_.dt / sub) + " s (" + failure + ")");
      }
      sub *= 2;
    }
    report.substeps = std::max(report.substeps, sub);
    for (std::size_t g = 0; g < grips_.size(); ++g) grip_start_[g] = grips_[g].target;  // the next step starts there
    time_ += options_.dt;
    ++steps_;
  }
  report.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return report;
}

double FemImplicitDynamics::kinetic_energy() const {
  double e = 0;
  for (std::size_t d = 0; d < v_.size(); ++d) e += 0.5 * model_.node_mass[d / 3] * v_[d] * v_[d];
  return e;
}

double FemImplicitDynamics::strain_energy() const { return fem_strain_energy(model_, u_); }

void FemImplicitDynamics::restore_state(const std::vector<double>& u, const std::vector<double>& v, double time, int64_t steps) {
  if (u.size() != u_.size() || v.size() != u_.size()) throw InputError("fem implicit", "state", "expected #N x 3 displacements and velocities");
  for (size_t i = 0; i < u.size(); ++i)
    if (!std::isfinite(u[i]) || !std::isfinite(v[i])) throw InputError("fem implicit", "state", "a value is not finite");
  u_ = u;
  v_ = v;
  time_ = time;
  steps_ = steps;
}

}  // namespace ctsurg::sim
