// The static integrator (fem_integrator.h): a quasi-static sequence, each frame the equilibrium under
// that frame's grabs, forces and gravity, warm-started from the previous frame. Which solve:
//   - with options.local_region_mm, Newton within that geodesic radius of the tools' nodes and the rest
//     from the linear model factorised once (fem_local_region.h; the supports must hold the model);
//   - the linear law on linear tets, where the supports alone hold the model: the stiffness factorised
//     once, a condensed solve each frame (fem_linear_static_solver.h);
//   - otherwise Newton (fem_static_solver.h: direct or iterative solves, the factor kept across frames),
//     which also holds a grab that completes the supports (a roller and a grab). With quasi-Newton
//     (options.newton.nonlinear) a frame starts from the last two frames' linear extrapolation, 2 u_k -
//     u_{k-1}, while the grabs hold the same nodes and the volume grips the same elements (a drag: the
//     tool's steady motion carried over).
// Volume grips (fem_grip.h) are loads of the Newton solve: a frame with one goes to Newton even where
// the linear law's condensation would otherwise solve it (that holds node sets only).
#include "ctsurg/core/error.h"
#include "ctsurg/sim/fem/fem_engine.h"
#include "ctsurg/sim/fem/fem_forces.h"
#include "ctsurg/sim/fem/fem_linear_static_solver.h"
#include "ctsurg/sim/fem/fem_local_region.h"
#include "fem_integrators.h"
#include "fem_rigid_modes.h"

#include <numeric>

namespace ctsurg::sim {
namespace {

class FemStaticIntegrator final : public FemIntegrator {
 public:
  FemStaticIntegrator(const FemModel& model, const FemBoundaryConditions& supports, const FemEngineOptions& options, Backend backend)
      : model_(model), options_(options) {
    if (supports.fixed_nodes.empty() && supports.fixed_components.empty()) {
      throw InputError(options.where, "fixed", "a static FEM problem needs fixed nodes (the system is singular otherwise)");
    }
    bc_ = supports;
    FemStaticOptions newton = options.newton;
    newton.threads = options.threads;
    newton.initial_displacements.clear();
    // The linear law's condensation (fem_linear_static_solver.h) needs supports that hold the model on
    // their own; where a grab completes them (a roller and a grab), Newton's solver holds both.
    std::vector<uint8_t> supported(3 * static_cast<size_t>(model.node_count()), 0);
    for (const int32_t n : supports.fixed_nodes) supported[3 * static_cast<size_t>(n)] = supported[3 * static_cast<size_t>(n) + 1] =
        supported[3 * static_cast<size_t>(n) + 2] = 1;
    for (const int32_t c : supports.fixed_components) supported[static_cast<size_t>(c)] = 1;
    const bool supports_hold = free_rigid_modes(model, supported, fem_bounding_diagonal(model)).empty();
    if (options.local_region_mm) {
      // The region's Newton solves with the model's law; the rest from the linear model, factorised once.
      if (!supports_hold) {
        throw InputError(options.where, "local_region", "the global linear model of a local region is factorised once, so the fixed "
                                                        "regions alone must hold the model (no rigid motion left to a grab)");
      }
      FemLocalRegionOptions lo;
      lo.radius_mm = *options.local_region_mm;
      lo.newton = newton;
      lo.linear.threads = options.threads;
      lo.balance_iterations = options.local_region_balance_iterations;
      local_ = std::make_unique<FemLocalRegionSolver>(model, bc_, lo, backend);
      if (options.note) {
        options.note("FEM local region: Newton within " + std::to_string(lo.radius_mm) + " mm (geodesic) of the tools' nodes, the rest linear (" +
                     std::to_string(local_->linear_stats().factor_nonzeros) + " non-zeros factorised once, " +
                     std::to_string(local_->linear_stats().factor_seconds) + " s)");
      }
      return;
    }
    if (model.every_law(FemLaw::linear) && model.order == 1 && newton.linear_solve != FemLinearSolve::iterative && supports_hold) {
      FemLinearSolverOptions lo;
      lo.threads = options.threads;
      linear_ = std::make_unique<FemLinearStaticSolver>(model, bc_, lo);
      if (options.note) {
        options.note("FEM linear static: stiffness factorised once (" + std::to_string(linear_->stats().factor_nonzeros) +
                     " non-zeros, " + std::to_string(linear_->stats().factor_seconds) + " s); each frame a condensed solve");
      }
    } else {
      newton_solver_ = std::make_unique<FemStaticSolver>(model, newton, backend);
    }
    newton_options_ = newton;
    backend_ = backend;
  }

  bool quasi_static() const override { return true; }
  double dt() const override { return 0; }
  double time() const override { return time_; }

  FemAdvance equilibrium(FemToolHolds& holds, const std::vector<ToolInput>& tools, double time, bool warm_start,
                         std::vector<double>& u) override {
    holds.update_grabs(tools, time, u, true, grab_nodes_, grab_displacements_);
    holds.update_forces(tools, u, true);
    FemLoads loads;
    loads.gravity = options_.gravity;
    loads.forces = holds.nodal_forces();
    holds.update_grips(tools, time, u, true, loads.grips);
    // The linear law's condensation holds node sets only: a grip's frames go to Newton (one step on
    // the linear law), made when the first grip captures.
    const bool by_newton = !local_ && (!linear_ || !loads.grips.empty());
    if (by_newton && !newton_solver_) newton_solver_ = std::make_unique<FemStaticSolver>(model_, newton_options_, backend_);
    FemStaticResult r;
    if (local_) {
      // The region grows from every node a tool holds or loads, as far as that tool's radius (its own
      // local_region_mm, or the engine's).
      seeds_.clear();
      seed_radii_.clear();
      for (size_t t = 0; t < tools.size(); ++t) {
        if (tools[t].acts != ToolPrimitive::hold && tools[t].acts != ToolPrimitive::load) continue;
        const std::vector<int32_t>& held = holds.held_nodes(t);
        seeds_.insert(seeds_.end(), held.begin(), held.end());
        seed_radii_.resize(seeds_.size(), tools[t].local_region_mm > 0 ? tools[t].local_region_mm : *options_.local_region_mm);
      }
      r = local_->solve(grab_nodes_, grab_displacements_, loads, seeds_, warm_start ? &u : nullptr, &seed_radii_);
    } else if (!by_newton) {
      r = linear_->solve(grab_nodes_, grab_displacements_, loads);
    } else {
      bc_.prescribed_nodes = grab_nodes_;
      bc_.prescribed_displacements = grab_displacements_;
      const std::vector<double>* start = warm_start ? &u : nullptr;  // warm start from the previous frame
      const bool extrapolate = options_.newton.nonlinear == FemNonlinearSolve::quasi_newton && warm_start &&
                               previous_u_.size() == u.size() && grab_nodes_ == previous_grab_nodes_ && same_grips(loads.grips);
      if (extrapolate) {
        extrapolated_.resize(u.size());
        for (size_t d = 0; d < u.size(); ++d) extrapolated_[d] = 2 * u[d] - previous_u_[d];
        start = &extrapolated_;
      }
      r = newton_solver_->solve(bc_, loads, start);
      if (options_.newton.nonlinear == FemNonlinearSolve::quasi_newton) {
        previous_u_ = u;
        previous_grab_nodes_ = grab_nodes_;
        previous_grip_elements_.clear();
        for (const FemGrip& g : loads.grips) previous_grip_elements_.push_back(g.elements);
      }
    }
    if (!r.report.converged) {
      throw RuntimeError(options_.where + ": the static FEM solve at t = " + std::to_string(time) +
                         " s did not converge: relative residual " + std::to_string(r.report.relative_residual) + " after " +
                         std::to_string(r.report.newton_iterations) + " Newton iterations");
    }
    u = std::move(r.displacements);
    reactions_ = std::move(r.reactions);
    time_ = time;
    FemAdvance a;
    a.newton_iterations = r.report.newton_iterations + r.report.quasi_newton_iterations;  // the nonlinear iterations
    a.cg_iterations = std::accumulate(r.report.cg_iterations.begin(), r.report.cg_iterations.end(), 0);
    a.solver_error_mm = r.report.error_estimate_mm;
    return a;
  }

  void displacements(std::vector<double>&) const override {}  // the engine's u is the last solve's
  double strain_energy(const FemModel& model, const std::vector<double>& u) const override { return fem_strain_energy(model, u); }

  FemCarriedState carried_state() const override {
    FemCarriedState s;
    s.time = time_;
    return s;
  }
  void restore(const FemCarriedState& s, const std::vector<double>&, const std::vector<double>&) override { time_ = s.time; }
  const FemLocalRegionSolver* local_region() const override { return local_.get(); }
  const std::vector<double>* reactions() const override { return &reactions_; }

 private:
  const FemModel& model_;
  FemEngineOptions options_;
  FemBoundaryConditions bc_;
  std::unique_ptr<FemLinearStaticSolver> linear_;
  std::unique_ptr<FemStaticSolver> newton_solver_;
  std::unique_ptr<FemLocalRegionSolver> local_;
  FemStaticOptions newton_options_;
  Backend backend_ = Backend::cpu;
  std::vector<double> reactions_;  // the last frame's (#N x 3 uN)
  double time_ = 0;
  std::vector<int32_t> grab_nodes_;  // scratch
  std::vector<double> grab_displacements_;
  // Quasi-Newton: the frame before the last (its u and grabbed nodes), and the extrapolated start.
  std::vector<double> previous_u_, extrapolated_;
  std::vector<int32_t> previous_grab_nodes_;
  std::vector<std::vector<int32_t>> previous_grip_elements_;  // the last frame's grips (a capture or release restarts)
  bool same_grips(const std::vector<FemGrip>& grips) const {
    if (grips.size() != previous_grip_elements_.size()) return false;
    for (std::size_t g = 0; g < grips.size(); ++g)
      if (grips[g].elements != previous_grip_elements_[g]) return false;
    return true;
  }
  std::vector<int32_t> seeds_;        // scratch: the tools' nodes the local region grows from
  std::vector<double> seed_radii_;    // scratch: each seed's radius (its tool's local_region_mm or the engine's), mm
};

}  // namespace

std::unique_ptr<FemIntegrator> make_fem_static_integrator(const FemModel& model, const FemBoundaryConditions& supports,
                                                          const FemEngineOptions& options, Backend backend) {
  return std::make_unique<FemStaticIntegrator>(model, supports, options, backend);
}

}  // namespace ctsurg::sim
