// Quasi-Newton iterations of FemNewton (fem_newton.h; FemNonlinearSolve::quasi_newton in
// fem_static_solver.h): L-BFGS on the potential E(u) whose negative gradient is the residual r(u)
// (Nocedal and Wright, Numerical Optimization, 2nd ed., algorithm 7.4 and 7.5), with the initial
// inverse Hessian H_0 = J_0^-1, J_0 = K(0) + c_m M + c_b K(0) the rest tangent on the free components,
// factorised once per held set and step coefficients (Liu, Bouaziz and Kavan 2017, section 4: the rest
// Hessian as H_0 makes L-BFGS robust on stiff meshes, where a scaled identity needs thousands of
// iterations).
//
// An iteration: the two-loop recursion over the last options.lbfgs_history pairs (s_k = u_{k+1} - u_k,
// y_k = r_k - r_{k+1} on the free components), one pair of triangular solves with J_0's factor, the
// line search of Newton's iteration (alpha = 1, 1/2, ...: accepted when ||r|| decreases or the potential
// decreases by Armijo's rule; a trial that inverts an element is halved). A pair with y . s <= 0 (no
// curvature along the step: the potential is not convex there) is not kept, and a direction that is not
// one of descent restarts from H_0. The first iteration, while the held components lag their targets,
// is the lifted predictor with J_0: J_0,ff du_f = r_f - J_0,fh gap (Newton's lift with the rest tangent,
// a linear-elastic predictor), the longest step that inverts nothing. The stopping rule is Newton's: in
// millimetres (options.tolerance_mm: a full step moved no free component by more than the budget, and the
// residual's displacement ||r||_inf / mean(diag J_0) is below it too), or the relative rule.
//
// Cost per iteration: one force evaluation (plus one energy evaluation when the residual did not
// decrease), one forward and backward substitution with a single-precision copy of J_0's factor
// (sparse_cholesky.h: H_0 only preconditions, and the substitutions are bandwidth-bound); no element
// Hessian, no factorisation after the first frame of a held set. Measured in docs/benchmarks.md ("Quasi-Newton") against Newton to the same budget.
#include "fem_newton.h"

#include "ctsurg/core/elapsed_seconds.h"
#include "ctsurg/core/error.h"
#include "fem_cpu_kernels.h"
#include "sparse_cholesky.h"

#include <Eigen/Core>

#include <chrono>
#include <cmath>
#include <deque>

namespace ctsurg::sim {
namespace {

using QuasiNewtonClock = std::chrono::steady_clock;

// One L-BFGS pair: the step s, the change of the gradient y (= r_k - r_{k+1}), 1 / (y . s).
struct LbfgsPair {
  Eigen::VectorXd s, y;
  double rho = 0;
};

}  // namespace

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
  if (!lifting && (r.size() == 0 || rnorm <= o_.residual_tolerance * rep.reference_residual)) return true;  // already in equilibrium
  std::deque<LbfgsPair> pairs;
  std::vector<double> a(static_cast<std::size_t>(o_.lbfgs_history));
  const double rest_scale = 1 + terms_.stiffness_damping;
  for (int it = 0; it < o_.max_quasi_newton_iterations; ++it) {
    const auto t0 = QuasiNewtonClock::now();
    // The direction: H r by the two-loop recursion (H_0 = J_0^-1), or the lifted predictor.
    q = r;
    if (lifting) lift(gap, q, rest_kbuf_, rest_scale, nullptr, 0);
    for (std::size_t i = pairs.size(); i-- > 0;) {
      a[i] = pairs[i].rho * pairs[i].s.dot(q);
      q -= a[i] * pairs[i].y;
    }
    d.resize(q.size());
    cholesky_->solve_single(q.data(), d.data());
    for (std::size_t i = 0; i < pairs.size(); ++i) {
      const double b = pairs[i].rho * pairs[i].y.dot(d);
      d += (a[i] - b) * pairs[i].s;
    }
    double slope = lifting ? 0.0 : r.dot(d);  // -dE/dalpha at 0
    if (!lifting && !(slope > 0) && !pairs.empty()) {  // not a descent direction: restart from H_0
      pairs.clear();
      cholesky_->solve_single(r.data(), d.data());
      slope = r.dot(d);
    }
    rep.solve_seconds += seconds_since(t0);
    ++rep.quasi_newton_iterations;
    if (!d.allFinite()) {
      failure = "the quasi-Newton direction has non-finite values at load factor " + std::to_string(s);
      return false;
    }
    const double d_inf = d.size() ? d.lpNorm<Eigen::Infinity>() : 0.0;
    const LineSearch ls = line_search(u, d, gap, lifting, s, rnorm, slope, false, in_mm && d_inf <= o_.tolerance_mm, trial, r_trial);
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
        return true;
    } else if (rnorm <= o_.residual_tolerance * rep.reference_residual && step_inf <= o_.displacement_tolerance * diag_) {
      return true;
    }
  }
  failure = "quasi-Newton did not converge in " + std::to_string(o_.max_quasi_newton_iterations) + " iterations at load factor " +
            std::to_string(s) + " (relative residual " + std::to_string(rnorm / std::max(rep.reference_residual, 1e-300)) + ")";
  return false;
}

}  // namespace ctsurg::sim
