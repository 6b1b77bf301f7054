// The Newton machinery behind the static solver (fem_static_solver.h) and the implicit dynamics
// (fem_implicit_dynamics.h): one model, a set of held components (fixed, or moved to targets: a grab),
// and Newton iterations on
//
//   r(u) = f_int(u) + s f_ext - c_m M (u - y) - c_b K_n (u - u_n) - sum_g P_g (u - s g_g) = 0
//
// on the free components (s the load factor; the inertia and damping terms are zero for a static solve;
// P_g, g_g: the volume grips' penalty matrices and targets, fem_grip.h), with the tangent
// J = K(u) + c_m M + c_b K_n + sum_g P_g. Element tangents of the nonlinear laws are projected to positive
// semi-definite (options.projection: always, or when the exact J has no Cholesky factor), so J is
// positive definite whenever the held components remove every rigid motion, and its factor exists.
//
// Or quasi-Newton (options.nonlinear, src/fem_quasi_newton.cpp): L-BFGS on the same residual and
// potential, its initial inverse Hessian the factor of J_0 = K(0) + c_m M + c_b K(0), made once per held
// set and step coefficients.
//
// Linear solves. Direct: CHOLMOD (sparse_cholesky.h), the symbolic analysis once per held set, the
// numeric factor kept across Newton iterations and solves: while the tangent has moved since the
// factor was made, the factor preconditions conjugate gradients on the current tangent (a few
// iterations), and the tangent is factorised again only when those stop converging quickly. Iterative:
// Jacobi-preconditioned conjugate gradients (Eigen, or the device's with Backend::cuda). Automatic:
// direct while the factor fits in options.direct_max_bytes (default: half the memory available).
//
// Internal to sim/fem (no public header): the public solvers own one and check their arguments first.
#pragma once

#include "ctsurg/sim/fem/fem_grip.h"
#include "ctsurg/sim/fem/fem_model.h"
#include "ctsurg/sim/fem/fem_static_solver.h"
#include "ctsurg/sim/fem/kernels/fem_forces_impl.h"

#include <Eigen/SparseCore>

#include <deque>
#include <memory>
#include <string>
#include <vector>

namespace ctsurg::sim {

class DeviceConjugateGradient;
class SparseCholesky;

// What a time step adds to the static problem (all zero: static).
struct FemNewtonTerms {
  double mass = 0;                   // c_m, 1/s^2: inertia -c_m M (u - y), tangent + c_m M
  std::vector<double> inertia_target;  // y, #N x 3 mm (empty when mass = 0)
  double stiffness_damping = 0;      // c_b (dimensionless): -c_b K_n (u - u_n), tangent + c_b K_n
  std::vector<double> damping_origin;  // u_n, #N x 3 mm: K_n is the tangent there (empty when c_b = 0)
  // u_0, #N x 3 mm, or empty. Given: the unknown is a midpoint w, and each element's internal force at w
  // is replaced by its discrete gradient between u_0 and u_1 = 2 w - u_0 (Gonzalez 1996, "Time
  // integration and discrete Hamiltonian systems"; per element: Betsch and Steinmann 2001):
  //   f_e <- f_e(w) - c_e D_e,  c_e = (E_e(u_1) - E_e(u_0) + f_e(w) . D_e) / |D_e|^2,  D_e = u_1 - u_0 on e,
  // so that f . (u_1 - u_0) = -(E(u_1) - E(u_0)) exactly: the midpoint rule then conserves the energy
  // for every law (without it only for the linear one). The tangent ignores the correction (third
  // order in D); the residual then has no potential, so the line searches judge ||r|| alone.
  std::vector<double> gradient_origin;
};

class FemNewton {
 public:
  using SpMat = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;

  // where: names the solver in messages. device_cg: the device's conjugate gradients (Backend::cuda),
  // or null.
  FemNewton(const FemModel& model, const FemStaticOptions& options, DeviceConjugateGradient* device_cg, const char* where);
  ~FemNewton();
  FemNewton(const FemNewton&) = delete;
  FemNewton& operator=(const FemNewton&) = delete;

  // Held components (#N x 3 flags; nodes no tet uses are added) and their targets at load factor 1
  // (#N x 3 mm). Rebuilds the sparsity pattern and the factor's analysis only when the held set
  // changed. Without inertia terms (set_terms first for dynamics) throws InputError(where, "boundary
  // conditions", ...) naming the rigid motions that stay free.
  void set_held(const std::vector<uint8_t>& held, const std::vector<double>& target);
  // External forces at load factor 1: nodal forces plus the lumped weight (#N x 3 uN).
  void set_external(const std::vector<double>& external);
  void set_terms(FemNewtonTerms terms);
  // The volume grips (fem_grip.h) at load factor 1; call before set_held (a grip holds the model as a
  // support does). A change of their elements or matrices (a capture, a release) makes the factors new;
  // a change of targets alone (the tool moved) does not.
  void set_grips(const std::vector<FemGrip>& grips);
  const std::vector<uint8_t>& held() const { return held_; }

  // ||r|| at the held targets (free components at 0) under the full load: the scale of the relative
  // tolerances. Call after set_held, set_external and set_terms.
  double reference_residual();
  // Whether the solves read the reference residual: not quasi-Newton with the millimetre rule (its
  // callers then leave rep.reference_residual NaN, and newton() computes it if it goes on with Newton).
  bool needs_reference() const;
  // The forces (as forces()) of the last residual evaluated, when it was at exactly this u and s (the
  // solution a solve ended on: no second evaluation for the reactions); false otherwise.
  bool last_forces(const std::vector<double>& u, double s, std::vector<double>& out) const;
  // Newton at load factor s from u, whose held components may still sit at an earlier factor's
  // values (then the first iterations are a lifted predictor). True when converged; `failure` says
  // why not. Adds to rep's counters and histories.
  // With options.nonlinear quasi_newton (and a direct solve), L-BFGS first, then Newton from where it
  // stopped if it did not converge.
  bool newton(std::vector<double>& u, double s, FemStaticReport& rep, std::string& failure);
  // f_int + s f_ext (+ the dynamic terms) on every component (#N x 3 uN), at u. Returns the lowest
  // inverted element or -1.
  int32_t forces(const std::vector<double>& u, double s, std::vector<double>& out);
  // Whether forces() is the negative gradient of energy() (not with a discrete gradient).
  bool has_potential() const { return terms_.gradient_origin.empty(); }
  // The potential whose negative gradient is forces(): strain energy - s f_ext . u + the terms'
  // (c_m/2 |u - y|_M^2 + c_b/2 |u - u_n|_{K_n}^2), nJ; +inf where an element is inverted.
  double energy(const std::vector<double>& u, double s);
  // kw = K_n (u - u_n), the stiffness damping's product (#N x 3).
  void damping_product(const std::vector<double>& u, std::vector<double>& kw) const;

  bool direct() const { return direct_; }
  int64_t factor_bytes() const;
  int32_t free_components() const { return static_cast<int32_t>(k_.rows()); }

 private:
  int32_t residual(const std::vector<double>& u, double s, Eigen::VectorXd& r);
  int32_t assemble(const std::vector<double>& u, bool project);
  int solve_linear(const Eigen::VectorXd& b, Eigen::VectorXd& du, double tolerance, FemStaticReport& rep);
  int solve_iterative(const Eigen::VectorXd& b, Eigen::VectorXd& du, double tolerance);
  int solve_direct(const Eigen::VectorXd& b, Eigen::VectorXd& du, double tolerance, FemStaticReport& rep);
  bool held_gap(const std::vector<double>& u, double s, std::vector<double>& gap) const;
  // b -= J_fh gap from element matrices k (+ cb kn when kn is given).
  void lift(const std::vector<double>& gap, Eigen::VectorXd& b, const std::vector<double>& k, double scale,
            const std::vector<double>* kn, double cb) const;
  bool newton_iterations(std::vector<double>& u, double s, FemStaticReport& rep, std::string& failure);
  // The residual where an iteration starts (r, its norm, recorded in rep); false, with `failure`, when u
  // inverts an element.
  bool first_residual(const std::vector<double>& u, double s, Eigen::VectorXd& r, double& rnorm, FemStaticReport& rep, std::string& failure);
  // The backtracking line search of both iterations: u + alpha du (alpha = 1, 1/2, ...; while lifting the
  // held components move alpha of their gap, exactly to their targets at alpha = 1) until the trial
  // inverts nothing and: lifts, or ||r|| < bar, or accept_any, or alpha = 1 and accept_full, or (with a
  // potential and slope > 0) Armijo's decrease. trial and r_trial hold the accepted trial.
  // secant (quasi-Newton's): after a trial that inverted nothing and was not accepted, the next alpha is
  // where the potential's slope along du, interpolated linearly between 0 (-slope) and the trial
  // (-r_trial . du), vanishes, kept in [0.1, 0.5] of the trial's alpha, instead of half of it (measured on
  // the live heart's drag, with the kept L-BFGS pairs: a frame's force evaluations from 8.6 to 5.7;
  // docs/fem.md "Quasi-Newton").
  struct LineSearch {
    double alpha = 1;
    bool accepted = false;
    int32_t inverted = -1;  // the last trial's lowest inverted element, or -1
  };
  LineSearch line_search(const std::vector<double>& u, const Eigen::VectorXd& du, const std::vector<double>& gap, bool lifting, double s,
                         double bar, double slope, bool accept_any, bool accept_full, bool secant, std::vector<double>& trial,
                         Eigen::VectorXd& r_trial);
  // fem_quasi_newton.cpp: L-BFGS at load factor s (true when converged; u stays a valid state either way).
  bool quasi_newton(std::vector<double>& u, double s, FemStaticReport& rep, std::string& failure);
  void factor_rest();  // J_0 into k_ and its factor (quasi-Newton's initial inverse Hessian)
  // The largest nodal displacement (mm) of a step on the free components.
  double largest_nodal_step(const Eigen::VectorXd& d) const;
  mutable std::vector<double> node_step_;  // its scratch: squared nodal displacements
  // k_'s values from element matrices: scale sum(kbuf (+ cb kbuf_n)) per non-zero, + c_m M on the
  // diagonal; mean_diagonal_ of the result.
  void gather_system(const std::vector<double>& kbuf, double scale, const std::vector<double>* kbuf_n, double cb);
  void index_grips();  // grip_slots_ from the grips and the pattern
  void build_system();
  void damping_tangent();
  std::string node_of_column(int64_t column) const;

  const FemModel& m_;
  FemStaticOptions o_;
  DeviceConjugateGradient* device_cg_;
  std::string where_;
  int threads_;
  double diag_ = 1;             // bounding-box diagonal, mm
  std::vector<uint8_t> held_;   // #N x 3
  std::vector<double> target_, external_, corner_, forces_, all_forces_, kbuf_, kbuf_n_, element_energy_, damping_kw_;
  FemNewtonTerms terms_;
  std::vector<FemGrip> grips_;
  std::vector<std::pair<int64_t, double>> grip_slots_;  // (non-zero of k_, value) of the grips' P on the free components
  mutable std::vector<double> grip_scratch_;  // lift's P gap
  FemElementView<double> el_{};
  int npe_ = 4, ne_ = 12;  // nodes and unknowns per element (quadratic: 10, 30)
  // The free components' system: pattern, each non-zero's element-matrix contributions, the diagonal's
  // positions, the component <-> free index maps.
  std::vector<int32_t> free_index_, free_component_;
  SpMat k_;
  std::vector<int64_t> contrib_offsets_, contrib_;
  std::vector<int64_t> diagonal_;
  double mean_diagonal_ = 1;    // uN/mm, of the last assembly: a residual's displacement scale
  bool direct_ = false;
  std::unique_ptr<SparseCholesky> cholesky_;
  bool factor_current_ = false; // the factor is of the current values
  bool damping_ready_ = false;  // kbuf_n_ holds K_n
  bool projecting_ = false;     // this Newton solve assembles projected tangents (the exact one had no factor)
  const std::vector<double>* assembled_at_ = nullptr;  // the u of the last assembly (for a projected re-assembly)
  // Quasi-Newton: the rest element tangents K(0) (computed once), whether the factor is of J_0 for the
  // current held set, and the coefficients it was made with.
  std::vector<double> rest_kbuf_;
  std::vector<double> last_u_;  // the u of the last residual() (its forces are all_forces_)
  double last_s_ = NAN;
  // The discrete gradient (FemNewtonTerms::gradient_origin): element energies at u_0 and scratch.
  std::vector<double> origin_energy_, end_energy_, end_u_, gradient_coefficient_;
  void discrete_gradient(const std::vector<double>& w);
  bool rest_factor_ = false;
  // L-BFGS's pairs (s_k = u_{k+1} - u_k, y_k = r_k - r_{k+1} on the free components, rho_k = 1 / y_k . s_k),
  // the newest last, kept across solves while J_0's factor is: the next frame or step starts with the
  // curvature the last one found (measured on the live heart's drag: a frame's force evaluations from
  // 8.6 to 6.7). Cleared with a new J_0 (a new held set, grip or step coefficients) and by a restart.
  struct LbfgsPair {
    Eigen::VectorXd s, y;
    double rho = 0;
  };
  std::deque<LbfgsPair> lbfgs_pairs_;
  double rest_mass_ = 0, rest_damping_ = 0;
  double rest_mean_diagonal_ = 1;  // mean(diag J_0): quasi-Newton's residual displacement scale
};

// "element e (rest centroid (x, y, z) mm)" in LPS, for messages.
std::string fem_element_text(const FemModel& model, int32_t e);

// Checks a static problem's arguments (InputError("fem static", field, ...)).
void validate_fem_static(const FemModel& model, const FemBoundaryConditions& bc, const FemLoads& loads,
                         const FemStaticOptions& options);

}  // namespace ctsurg::sim
