// Static equilibrium of a FemModel: Newton-Raphson on f_int(u) + f_ext = 0 (Huang et al., the FEM
// paper, eq. 1 and 8-10: R(a) = F, a+ = a + K^-1 (F - R(a))), with Dirichlet conditions (fixed nodes,
// fixed single components, prescribed displacements of a node set: a grab), load stepping and a
// backtracking line search.
//
// Each Newton iteration assembles the tangent stiffness K = -d f_int / du (element 12 x 12 Hessians,
// fem_element_impl.h; for St. Venant-Kirchhoff and Neo-Hookean projected to positive semi-definite per
// element where the exact tangent has no Cholesky factor: see `projection`) over the free components into a sparse
// matrix (the sparsity pattern is built once per held set; values are gathered per non-zero from the
// element matrices, deterministic) and solves K du = r, r = f_int + f_ext on the free components:
//   direct      CHOLMOD's supernodal Cholesky (src/sparse_cholesky.h): analysed once per held set,
//               the factor kept across Newton iterations and solves; while the tangent has moved since,
//               the old factor preconditions conjugate gradients on the new tangent, and the tangent is
//               factorised again only when those need more than reuse_cg_iterations;
//   iterative   Jacobi-preconditioned conjugate gradients in double (the paper's section 4;
//               Eigen::ConjugateGradient, full matrix, OpenMP products; on the device with cuda);
//   automatic   direct while its factor fits in direct_max_bytes (iterative on the cuda backend).
// Then u <- u + alpha du with alpha = 1, 1/2, 1/4, ... until ||r|| decreases (a trial that inverts an
// element counts as an increase). Held components are not moved ahead of the free ones: while they
// lag their targets (each load increment raises them), the iteration is a lifted predictor,
// K_ff du_f = r_f - K_fh (target_h - u_h), moving both together (5 Newton iterations instead of 10-28
// for a 10 % grab, docs/fem.md).
//
// Convergence of a load step: ||r||_2 <= residual_tolerance * r_ref, r_ref = ||r|| at u = 0 under the
// full load (the full forces and prescribed displacements), and ||alpha du||_inf <=
// displacement_tolerance * D, D = the diagonal of the rest mesh's bounding box. Or, with
// tolerance_mm > 0, in millimetres: a full step (alpha = 1) moved no free component by more than
// tolerance_mm, and the residual's displacement, ||r||_inf / mean(diag K), is below tolerance_mm too. The linear material
// takes exactly one Newton step (K is exact; the accuracy is the CG tolerance's, report.relative_residual
// says what it reached). A step that does not converge within
// max_newton_iterations, or whose line search fails, is retried from the last converged state with
// half the load increment, down to 1 / 2^max_halvings of the load; then RuntimeError.
//
// Units: displacements mm, forces uN (g mm/s^2), gravity mm/s^2; arrays #N x 3 row-major.
#pragma once

#include "ctsurg/sim/base/backend.h"
#include "ctsurg/sim/fem/fem_grip.h"
#include "ctsurg/sim/fem/fem_model.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

namespace ctsurg::sim {

struct FemBoundaryConditions {
  std::vector<int32_t> fixed_nodes;               // all three components held at 0
  std::vector<int32_t> fixed_components;          // 3 node + axis (0 x, 1 y, 2 z) held at 0 (rollers, symmetry)
  std::vector<int32_t> prescribed_nodes;          // #G nodes moved to prescribed_displacements (a grab)
  std::vector<double> prescribed_displacements;   // #G x 3 mm
};

struct FemLoads {
  std::vector<double> forces;                     // #N x 3 uN external nodal forces, or empty (none)
  std::array<double, 3> gravity{0, 0, 0};         // mm/s^2, applied as lumped body force m_i g
  // Volume grips (fem_grip.h): penalties that pull the material inside each tool to its target (scaled
  // by the load factor as the held targets are). A grip holds the model as a support does, so a problem
  // whose supports and grips together remove every rigid motion is definite.
  std::vector<FemGrip> grips;
};

enum class FemPreconditioner { diagonal, incomplete_cholesky };
enum class FemLinearSolve { automatic, direct, iterative };  // see above
// The projection of St. Venant-Kirchhoff and Neo-Hookean element tangents to positive semi-definite
// (src/fem_tangent_projection.h): never; when needed (direct solves: a Newton iteration whose exact
// tangent has no Cholesky factor is assembled again projected, so Newton keeps its quadratic
// convergence wherever the exact tangent is positive definite); always.
enum class FemTangentProjection { never, when_needed, always };
// The nonlinear iteration. newton: above. quasi_newton: L-BFGS (Nocedal and Wright, Numerical
// Optimization, algorithm 7.4) whose initial inverse Hessian is the factor of the rest tangent K_0 (+ the
// time step's c_m M), made once per held set and kept across iterations, frames and steps (Liu, Bouaziz
// and Kavan 2017, "Quasi-Newton Methods for Real-time Simulation of Hyperelastic Materials"): an
// iteration costs one force evaluation and one pair of triangular solves, no element Hessian and no
// factorisation, where Newton assembles the tangent every iteration. Its first step lifts the held
// components with K_0 as Newton's lifts them with the tangent; the line search and the stopping rule are
// Newton's. Needs the direct solve (an iterative one falls back to newton) and a potential (the implicit
// midpoint scheme's discrete gradient has none: its steps use newton); an iteration count past
// max_quasi_newton_iterations continues with Newton from where it stopped (report.quasi_newton_fallbacks),
// so a solve converges wherever Newton's does (src/fem_quasi_newton.cpp).
enum class FemNonlinearSolve { newton, quasi_newton };

struct FemStaticOptions {
  double residual_tolerance = 1e-8;      // relative to r_ref (see above)
  double displacement_tolerance = 1e-8;  // relative to the bounding-box diagonal
  int max_newton_iterations = 25;        // per load step
  int load_steps = 1;                    // initial number of equal load increments (>= 1)
  int max_halvings = 8;                  // halvings of a failed increment before giving up
  int max_line_search = 8;               // halvings of alpha
  double cg_tolerance = 1e-10;           // relative residual of each linear solve, ||K du - r|| / ||r||
  // Nonlinear laws: solve each Newton step only to min(1e-2, ||r|| / r_ref) (at least cg_tolerance),
  // an Eisenstat-Walker-style forcing term; false: cg_tolerance always. The linear law ignores it.
  bool inexact_newton = true;
  int cg_max_iterations = 0;             // 0 = Eigen's default (2 x free components)
  FemPreconditioner preconditioner = FemPreconditioner::diagonal;
  int threads = 0;                       // 0 = OpenMP's default
  // #N x 3 mm where Newton starts (a warm start: the previous frame's solution in a quasi-static
  // sequence), or empty: the rest state. A warm start tries the full load at once; if that fails it
  // falls back to load stepping from rest (report.warm_start_failed).
  std::vector<double> initial_displacements;
  FemLinearSolve linear_solve = FemLinearSolve::automatic;
  double tolerance_mm = 0;               // > 0: the stopping rule in millimetres (see above)
  FemTangentProjection projection = FemTangentProjection::when_needed;
  int64_t direct_max_bytes = 0;          // automatic: the direct solve while its factor fits (0: half the memory available)
  int reuse_cg_iterations = 12;          // direct: CG iterations on an old factor before refactorising
  FemNonlinearSolve nonlinear = FemNonlinearSolve::newton;  // see above
  int lbfgs_history = 5;                 // quasi_newton: the (s, y) pairs kept, [1, 50]
  int max_quasi_newton_iterations = 60;  // quasi_newton: per load step, then Newton
  // quasi_newton: report.error_estimate_mm at the end of each load step (one more substitution; the
  // implicit dynamics, which has no use for it, turns it off).
  bool estimate_error = true;
};

struct FemStaticReport {
  bool converged = false;
  int load_steps = 0;                     // accepted load increments
  int halvings = 0;                       // failed increments that were halved
  int newton_iterations = 0;              // all Newton iterations, failed increments included
  std::vector<int> cg_iterations;         // per Newton iteration
  std::vector<double> residual_history;   // ||r||_2 (uN) before the first and after every iteration
  std::vector<double> load_factors;       // the load factor (0, 1] of every accepted increment
  double reference_residual = 0;          // r_ref, uN (NaN: not needed, quasi-Newton with tolerance_mm)
  double relative_residual = 0;           // final ||r|| / r_ref (NaN where r_ref is)
  double seconds = 0;                     // wall time of the whole solve
  double assembly_seconds = 0;            // element stiffnesses + sparse assembly
  double solve_seconds = 0;               // preconditioner + CG
  int free_components = 0;                // unknowns of the linear systems
  bool warm_start_failed = false;         // options.initial_displacements given, but Newton fell back to rest
  bool direct = false;                    // the linear solves were direct (CHOLMOD)
  int factorizations = 0;                 // numeric factorisations in this solve
  int64_t factor_bytes = 0;               // the factor's size (direct)
  int quasi_newton_iterations = 0;        // quasi_newton: L-BFGS iterations (the lift included)
  int quasi_newton_fallbacks = 0;         // quasi_newton: load steps that went on with Newton
  // quasi_newton: the estimate of the solution's distance from the converged one where the last load
  // step ended: the largest nodal displacement (mm) of the step L-BFGS would take next (H r, its inverse
  // Hessian applied to the last residual; one more substitution). NaN where not estimated (Newton, or a
  // step that went on with Newton).
  double error_estimate_mm = NAN;
};

struct FemStaticResult {
  std::vector<double> displacements;  // #N x 3 mm
  std::vector<double> reactions;      // #N x 3 uN: -(f_int + f_ext) on held components, 0 elsewhere
  FemStaticReport report;
};

// backend cuda: the same Newton iterations with the conjugate gradients on the device (Jacobi, Eigen's
// iteration and stopping rule; src/device_conjugate_gradient.h); InputError("fem static", "backend",
// ...) where cuda cannot run, InputError(..., "preconditioner", ...) for incomplete_cholesky with cuda.
// Throws InputError("fem static", field, ...) before solving: initial_displacements not #N x 3 or not
// finite ("initial_displacements"), node ids out of range or
// prescribed_displacements not #G x 3 ("fixed_nodes", "fixed_components", "prescribed_nodes",
// "prescribed_displacements"), forces not #N x 3 or not finite ("forces"), options out of range
// (their names), and held components that leave a rigid motion free ("boundary conditions": the
// stiffness would be singular; at least 3 non-collinear held nodes, or equivalent components, are
// needed). Throws RuntimeError when a load increment fails after max_halvings halvings (the message
// names the load factor and, if the cause was one, the inverted element).
FemStaticResult solve_fem_static(const FemModel& model, const FemBoundaryConditions& bc, const FemLoads& loads,
                                 const FemStaticOptions& options = {}, Backend backend = Backend::cpu);

class FemNewton;
class DeviceConjugateGradient;

// The same solve, many times on one model (a quasi-static sequence: a frame after another): the
// sparsity pattern and the factor's analysis are kept while the held set stays the same, and the last
// factor is kept for the next solve (as the conjugate gradients' preconditioner while the tangent
// differs). Each solve warm-starts from `initial` (#N x 3 mm) when given. Arguments and errors as
// solve_fem_static. The model must outlive the solver.
class FemStaticSolver {
 public:
  FemStaticSolver(const FemModel& model, const FemStaticOptions& options = {}, Backend backend = Backend::cpu);
  ~FemStaticSolver();
  FemStaticSolver(const FemStaticSolver&) = delete;
  FemStaticSolver& operator=(const FemStaticSolver&) = delete;

  FemStaticResult solve(const FemBoundaryConditions& bc, const FemLoads& loads, const std::vector<double>* initial = nullptr);
  const FemStaticOptions& options() const { return options_; }

 private:
  const FemModel& model_;
  FemStaticOptions options_;
  std::unique_ptr<DeviceConjugateGradient> device_cg_;
  std::unique_ptr<FemNewton> newton_;
};

}  // namespace ctsurg::sim
