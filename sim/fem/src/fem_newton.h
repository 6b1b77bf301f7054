// The Newton machinery behind the static solver (fem_static_solver.h) and the implicit dynamics
// (fem_implicit_dynamics.h): one model, a set of held components (fixed, or moved to targets: a grab),
// and Newton iterations on
//
//   r(u) = f_int(u) + s f_ext - c_m M (u - y) - c_b K_n (u - u_n) = 0      on the free components
//
// (s the load factor; the inertia and damping terms are zero for a static solve), with the tangent
// J = K(u) + c_m M + c_b K_n. Element tangents of the nonlinear laws are projected to positive
// semi-definite (options.projection: always, or when the exact J has no Cholesky factor), so J is
// positive definite whenever the held components remove every rigid motion, and its factor exists.
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

#include "ctsurg/sim/fem/fem_model.h"
#include "ctsurg/sim/fem/fem_static_solver.h"
#include "ctsurg/sim/fem/kernels/fem_forces_impl.h"

#include <Eigen/SparseCore>

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
  const std::vector<uint8_t>& held() const { return held_; }

  // ||r|| at the held targets (free components at 0) under the full load: the scale of the relative
  // tolerances. Call after set_held, set_external and set_terms.
  double reference_residual();
  // Newton at load factor s from u, whose held components may still sit at an earlier factor's
  // values (then the first iterations are a lifted predictor). True when converged; `failure` says
  // why not. Adds to rep's counters and histories.
  bool newton(std::vector<double>& u, double s, FemStaticReport& rep, std::string& failure);
  // f_int + s f_ext (+ the dynamic terms) on every component (#N x 3 uN), at u. Returns the lowest
  // inverted element or -1.
  int32_t forces(const std::vector<double>& u, double s, std::vector<double>& out);
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
  void lift(const std::vector<double>& gap, Eigen::VectorXd& b) const;
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
};

// Checks a static problem's arguments (InputError("fem static", field, ...)).
void validate_fem_static(const FemModel& model, const FemBoundaryConditions& bc, const FemLoads& loads,
                         const FemStaticOptions& options);

}  // namespace ctsurg::sim
