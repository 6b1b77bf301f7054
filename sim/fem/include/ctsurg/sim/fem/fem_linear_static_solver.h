// Linear-elastic static equilibrium for many solves on one model: a quasi-static scenario solves once
// per frame while a grab or a force moves, on a model whose supports (fixed nodes) never change. The
// stiffness K of the linear material is constant, so it is factorised once and each solve reuses the
// factor. This is the condensation that the FEM paper (Huang et al., section 5) names as its next step
// (after Bro-Nielsen and Cotin, 1996), done exactly rather than by reducing the mesh:
//
//   K_ss = L L^T            K restricted to the free components s (all components of used nodes that
//                           no support holds); CHOLMOD's supernodal Cholesky (src/sparse_cholesky.h), at
//                           construction.
//   c_j = K_ss^-1 e_j       the response to a unit force on component j ("columns"), computed the first
//                           time a node is grabbed or loaded (the new columns in one solve with many
//                           right-hand sides) and kept for later solves.
//
// A solve with grabbed (prescribed) components p held at d and nodal forces f:
//   u_0 = K_ss^-1 f         from the columns of the loaded nodes (or one back-substitution when more
//                           nodes are loaded than max_force_nodes), plus gravity's column (K_ss^-1 M g,
//                           cached per gravity vector);
//   C_pp lambda = d - u_0,p (C_pp = the columns' rows at p: 3|G| x 3|G|, dense Cholesky, cached while
//                           the grabbed node set stays the same);
//   u = u_0 + C_:p lambda   (lambda are the grab's reaction forces).
// A grab of more than max_grab_nodes nodes (a band of a vessel's wall, a large clamp) would need 3|G|
// columns (|G| x |s| x 24 bytes, and |G| back-substitutions): instead K_ff (K_ss without p's rows and
// columns) is factorised once per grabbed node set and u_f = K_ff^-1 (f_f - K_fp d) (the same
// solution; an analysis and a factorisation like the construction's, kept while the set stays).
// This is the exact solution of K_ff u_f = f_f - K_fp d on f = s \ p (the constrained system), so a
// solve costs O(|s| |G|) multiply-adds instead of a sparse solve. Each solve then checks itself: one
// product with K gives the true residual on f, ||K u - f|| / r_ref (r_ref = the residual of u = d on p,
// 0 elsewhere); above residual_tolerance it refines (one back-substitution with the same constraint)
// up to max_refinements times, then reports converged = false.
//
// Use solve_fem_static (Newton, conjugate gradients) for one solve, or for the nonlinear materials;
// factorising pays from a few solves on (docs/fem.md has the break-even).
//
// Units: displacements mm, forces uN (g mm/s^2), gravity mm/s^2; arrays #N x 3 row-major.
#pragma once

#include "ctsurg/sim/fem/fem_model.h"
#include "ctsurg/sim/fem/fem_static_solver.h"

#include <cstdint>
#include <memory>
#include <vector>

namespace ctsurg::sim {

struct FemLinearSolverOptions {
  double residual_tolerance = 1e-10;  // relative residual a solve must reach (see above)
  int max_refinements = 2;            // refinement steps before a solve reports converged = false
  int max_force_nodes = 64;           // loaded nodes up to which forces use cached columns
  int max_grab_nodes = 64;            // grabbed nodes up to which grabs use columns (above: K_ff factorised)
  int threads = 0;                    // 0 = OpenMP's default (columns, products)
};

struct FemLinearSolverStats {
  double factor_seconds = 0;         // assembly, ordering and factorisation (construction)
  double column_seconds = 0;         // all columns computed so far (and the large grabs' K_ff factorisations)
  int64_t columns = 0;               // unit-force responses computed so far (3 per node, less supports)
  int64_t factor_nonzeros = 0;       // non-zeros of L
  int free_components = 0;           // |s|
};

class FemLinearStaticSolver {
 public:
  // every material of the model must be FemLaw::linear; supports.fixed_nodes and
  // supports.fixed_components are held at zero for every solve and must remove all rigid motions on
  // their own (grabs come and go with each solve); supports.prescribed_* must be empty. Throws
  // InputError("fem linear solver", field, ...): "material", "fixed_nodes", "fixed_components",
  // "prescribed_nodes", "boundary conditions" (singular), option names. The model must outlive this.
  FemLinearStaticSolver(const FemModel& model, const FemBoundaryConditions& supports, const FemLinearSolverOptions& options = {});
  ~FemLinearStaticSolver();
  FemLinearStaticSolver(const FemLinearStaticSolver&) = delete;
  FemLinearStaticSolver& operator=(const FemLinearStaticSolver&) = delete;

  // The equilibrium with `prescribed_nodes` (#G, not supported in every axis, no repeats) held at
  // `prescribed_displacements` (#G x 3 mm; a node's supported axes stay at 0 whatever they say) under `loads`. Throws InputError("fem linear solver",
  // field, ...) for bad arguments ("prescribed_nodes", "prescribed_displacements", "forces", "gravity").
  // The report: newton_iterations = 1 + refinements, cg_iterations empty (a direct solve),
  // relative_residual, seconds (this solve, columns computed for it included), solve_seconds (the
  // columns' share), free_components = |f|, converged.
  FemStaticResult solve(const std::vector<int32_t>& prescribed_nodes, const std::vector<double>& prescribed_displacements,
                        const FemLoads& loads);

  const FemLinearSolverStats& stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ctsurg::sim
