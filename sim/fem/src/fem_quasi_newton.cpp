// Quasi-Newton iterations of FemNewton (fem_newton.h; FemNonlinearSolve::quasi_newton in
// fem_static_solver.h): L-BFGS on the potential E(u) whose negative gradient is the residual r(u)
// (Nocedal and Wright, Numerical Optimization, 2nd ed., algorithm 7.4 and 7.5), with the initial
// inverse Hessian H_0 = J_0^-1, J_0 = K(0) + c_m M + c_b K(0) the rest tangent on the free components,
// factorised once per held set and step coefficients (Liu, Bouaziz and Kavan 2017, section 4: the rest
// Hessian as H_0 makes L-BFGS robust on stiff meshes, where a scaled identity needs thousands of
// iterations).
//
// An iteration: the two-loop recursion over the last options.lbfgs_history pairs (s_k = u_{k+1} - u_k,
// y_k = r_k - r_{k+1} on the free components; kept from one solve to the next while J_0 is, so a frame
// starts with the last frame's curvature), one pair of triangular solves with J_0's factor, the line
// search of Newton's iteration (alpha = 1 first: accepted when ||r|| decreases or the potential decreases
// by Armijo's rule; a trial that inverts an element is halved), whose next trial after a rejected one is
// the secant estimate of the potential's minimum along the direction (from the slope at the trial,
// -r_trial . d, which the trial's residual gives for free), in [0.1, 0.5] of the rejected alpha. A pair
// with y . s <= 0 (no curvature along the step: the potential is not convex there) is not kept, and a
// direction that is not one of descent restarts from H_0. The first iteration, while the held components lag their targets,
// is the lifted predictor with J_0: J_0,ff du_f = r_f - J_0,fh gap (Newton's lift with the rest tangent,
// a linear-elastic predictor), the longest step that inverts nothing. The stopping rule is Newton's: in
// millimetres (options.tolerance_mm: a full step moved no free component by more than the budget, and the
// residual's displacement ||r||_inf / mean(diag J_0) is below it too), or the relative rule.
//
// Where it converges, the step it would take next (H r: one more two-loop recursion and substitution) is
// its estimate of the error left, its largest nodal displacement in report.error_estimate_mm: what the
// live page shows a surgeon per frame (validated against a converged solve by bench/live_drag_error.sh).
//
// Cost per iteration: one force evaluation (plus one energy evaluation when the residual did not
// decrease), one forward and backward substitution with a single-precision form of J_0's factor
// (sparse_cholesky.h: H_0 only preconditions, and the substitutions are bandwidth-bound); no element
// Hessian, no factorisation after the first frame of a held set. Measured in docs/benchmarks.md ("Quasi-Newton") against Newton to the same budget.
#include "fem_newton.h"

#include "ctsurg/core/elapsed_seconds.h"
#include "ctsurg/core/error.h"
#include "fem_cpu_kernels.h"
#include "sparse_cholesky.h"

#include <Eigen/Core>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>

namespace ctsurg::sim {
namespace {

using QuasiNewtonClock = std::chrono::steady_clock;

}  // namespace

double FemNewton::largest_nodal_step(const Eigen::VectorXd& d) const {
  node_step_.assign(static_cast<std::size_t>(m_.node_count()), 0.0);
  for (std::size_t c = 0; c < free_component_.size(); ++c) {
    const double v = d[static_cast<Eigen::Index>(c)];
    node_step_[static_cast<std::size_t>(free_component_[c] / 3)] += v * v;
  }
  double most = 0;
  for (double v : node_step_) most = std::max(most, v);
  return std::sqrt(most);
}

void FemNewton::factor_rest() {
  if (rest_kbuf_.empty()) {
    const std::vector<double> rest(3 * static_cast<std::size_t>(m_.node_count()), 0.0);
    rest_kbuf_.resize(kbuf_.size());
    cpu::fem_stiffness(el_, rest.data(), rest_kbuf_.data(), threads_, o_.projection == FemTangentProjection::always);
  }
  gather_system(rest_kbuf_, 1 + terms_.stiffness_damping, nullptr, 0);  // c_b K_n taken at rest too
  rest_mean_diagonal_ = mean_diagonal_;
  const int64_t failed = cholesky_->factorize(k_.valuePtr());
  if (failed >= 0) {
    throw RuntimeError(where_ + ": the rest stiffness is not positive definite at " + node_of_column(failed) +
                       " (an element near it is degenerate, or the held components leave that part of the mesh free to move rigidly)");
  }
  cholesky_->make_single();  // H_0 only preconditions: the single-precision substitutions, half the traffic
  rest_factor_ = true;
  lbfgs_pairs_.clear();  // pairs of another J_0's problem
  factor_current_ = false;  // k_ holds J_0, not the tangent at any u
  rest_mass_ = terms_.mass;
  rest_damping_ = terms_.stiffness_damping;
}

bool FemNewton::quasi_newton(std::vector<double>& u, double s, FemStaticReport& rep, std::string& failure) {
  if (!rest_factor_) {
    const auto t0 = QuasiNewtonClock::now();
    factor_rest();
    ++rep.factorizations;
    rep.factor_bytes = cholesky_->factor_bytes();
    rep.solve_seconds += seconds_since(t0);
  }
  rep.direct = true;
  Eigen::VectorXd r, r_trial, q, d;
  double rnorm = 0;
  if (!first_residual(u, s, r, rnorm, rep, failure)) return false;
  const bool in_mm = o_.tolerance_mm > 0;
  std::vector<double> trial(u.size()), gap(u.size());
  bool lifting = held_gap(u, s, gap);
  std::deque<LbfgsPair>& pairs = lbfgs_pairs_;  // the last solve's, while J_0 is the same (fem_newton.h)
  std::vector<double> a(static_cast<std::size_t>(o_.lbfgs_history));
  const double rest_scale = 1 + terms_.stiffness_damping;
  // out = H in by the two-loop recursion (H_0 = J_0^-1); `in` is overwritten.
  const auto two_loop = [&](Eigen::VectorXd& in, Eigen::VectorXd& out) {
    for (std::size_t i = pairs.size(); i-- > 0;) {
      a[i] = pairs[i].rho * pairs[i].s.dot(in);
      in -= a[i] * pairs[i].y;
    }
    out.resize(in.size());
    cholesky_->solve_single(in.data(), out.data(), threads_);
    for (std::size_t i = 0; i < pairs.size(); ++i) {
      const double b = pairs[i].rho * pairs[i].y.dot(out);
      out += (a[i] - b) * pairs[i].s;
    }
  };
  // Converged: the next step's largest nodal displacement is the estimate of the error left.
  const auto converged = [&] {
    if (!o_.estimate_error) return true;
    const auto t0 = QuasiNewtonClock::now();
    q = r;
    two_loop(q, d);
    rep.error_estimate_mm = largest_nodal_step(d);
    rep.solve_seconds += seconds_since(t0);
    return true;
  };
  if (!lifting && (r.size() == 0 || rnorm <= o_.residual_tolerance * rep.reference_residual)) return converged();
  for (int it = 0; it < o_.max_quasi_newton_iterations; ++it) {
    const auto t0 = QuasiNewtonClock::now();
    // The direction: H r, or the lifted predictor.
    q = r;
    if (lifting) lift(gap, q, rest_kbuf_, rest_scale, nullptr, 0);
    two_loop(q, d);
    double slope = lifting ? 0.0 : r.dot(d);  // -dE/dalpha at 0
    if (!lifting && !(slope > 0) && !pairs.empty()) {  // not a descent direction: restart from H_0
      pairs.clear();
      q = r;
      two_loop(q, d);
      slope = r.dot(d);
    }
    rep.solve_seconds += seconds_since(t0);
    ++rep.quasi_newton_iterations;
    if (!d.allFinite()) {
      failure = "the quasi-Newton direction has non-finite values at load factor " + std::to_string(s);
      return false;
    }
    const double d_inf = d.size() ? d.lpNorm<Eigen::Infinity>() : 0.0;
    const LineSearch ls = line_search(u, d, gap, lifting, s, rnorm, slope, false, in_mm && d_inf <= o_.tolerance_mm, true, trial, r_trial);
    const double alpha = ls.alpha;
    const bool accepted = ls.accepted;
    const int32_t inverted = ls.inverted;
    if (!accepted) {
      failure = inverted >= 0 ? fem_element_text(m_, inverted) + " inverted in every quasi-Newton line-search trial at load factor " +
                                    std::to_string(s)
                              : "the quasi-Newton line search found no decrease at load factor " + std::to_string(s);
      return false;
    }
    if (!lifting) {  // a pair from a step of the free components alone (the held ones did not move)
      LbfgsPair p;
      p.s = alpha * d;
      p.y = r - r_trial;
      const double ys = p.y.dot(p.s);
      if (ys > 1e-12 * p.s.norm() * p.y.norm() && ys > 0) {
        p.rho = 1 / ys;
        if (static_cast<int>(pairs.size()) == o_.lbfgs_history) pairs.pop_front();
        pairs.push_back(std::move(p));
      }
    }
    u.swap(trial);
    r.swap(r_trial);
    rnorm = r.norm();
    rep.residual_history.push_back(rnorm);
    const double step_inf = alpha * d_inf;
    lifting = held_gap(u, s, gap);
    if (lifting) continue;
    if (in_mm) {
      if (alpha == 1 && step_inf <= o_.tolerance_mm && (r.size() == 0 || r.lpNorm<Eigen::Infinity>() / rest_mean_diagonal_ <= o_.tolerance_mm))
        return converged();
    } else if (rnorm <= o_.residual_tolerance * rep.reference_residual && step_inf <= o_.displacement_tolerance * diag_) {
      return converged();
    }
  }
  failure = "quasi-Newton did not converge in " + std::to_string(o_.max_quasi_newton_iterations) + " iterations at load factor " +
            std::to_string(s) + " (relative residual " + std::to_string(rnorm / std::max(rep.reference_residual, 1e-300)) + ")";
  return false;
}

}  // namespace ctsurg::sim
