// The implicit integrator (fem_integrator.h): backward Euler (fem_implicit_dynamics.h), Newton per step
// on the factorised tangent, steps of options.dt (default a frame, 1/60 s). The grabs are captured with
// the tool where it started within the step (a frame-long step must not lose the tool's motion over it,
// as capturing at the step's end would); forces as the explicit dynamics'.
#include "ctsurg/core/error.h"
#include "ctsurg/sim/fem/fem_engine.h"
#include "ctsurg/sim/fem/fem_implicit_dynamics.h"
#include "fem_integrators.h"

namespace ctsurg::sim {
namespace {

class FemImplicitIntegrator final : public FemIntegrator {
 public:
  FemImplicitIntegrator(const FemModel& model, const FemBoundaryConditions& supports, const FemEngineOptions& options, Backend backend) {
    FemImplicitOptions o;
    o.dt = options.dt > 0 ? options.dt : 1.0 / 60;
    o.mass_damping = options.mass_damping;
    o.stiffness_damping = options.stiffness_damping;
    o.scheme = options.implicit_scheme;
    o.gravity = options.gravity;
    o.threads = options.threads;
    o.newton = options.newton;
    implicit_ = std::make_unique<FemImplicitDynamics>(model, o, backend);
    implicit_->set_supports(supports.fixed_nodes, supports.fixed_components);
  }

  bool quasi_static() const override { return false; }
  double dt() const override { return implicit_->dt(); }
  double time() const override { return implicit_->time(); }

  FemAdvance advance(FemToolHolds& holds, const std::vector<ToolInput>& tools, int steps, std::vector<double>& u) override {
    const double t_next = implicit_->time() + implicit_->dt();
    if (holds.captures(tools)) displacements(u);  // a tool captures the nodes where they are now
    holds.update_grabs(tools, t_next, u, true, grab_nodes_, grab_displacements_);
    if (!grab_nodes_.empty()) {
      implicit_->set_prescribed(grab_nodes_, grab_displacements_);
    } else {
      implicit_->clear_prescribed();
    }
    holds.update_grips(tools, t_next, u, true, grips_);
    implicit_->set_grips(grips_);
    if (holds.update_forces(tools, u, false)) implicit_->set_external_forces(holds.nodal_forces());
    FemAdvance a;
    try {
      const FemImplicitStepReport r = implicit_->step(steps);
      a.newton_iterations = r.newton_iterations + r.quasi_newton_iterations;  // the nonlinear iterations
    } catch (const RuntimeError& e) {
      a.stability.stable = false;
      a.stability.time = implicit_->time();
      a.stability.message = e.what();
    }
    return a;
  }

  void displacements(std::vector<double>& u) const override { u = implicit_->displacements(); }
  double kinetic_energy() const override { return implicit_->kinetic_energy(); }
  double strain_energy(const FemModel&, const std::vector<double>&) const override { return implicit_->strain_energy(); }

  FemCarriedState carried_state() const override {
    FemCarriedState s;
    s.velocities = implicit_->velocities();
    s.time = implicit_->time();
    s.steps_taken = implicit_->steps_taken();
    return s;
  }
  void restore(const FemCarriedState& s, const std::vector<double>& u, const std::vector<double>& forces) override {
    implicit_->restore_state(u, s.velocities, s.time, s.steps_taken);
    if (!forces.empty()) implicit_->set_external_forces(forces);
  }

 private:
  std::unique_ptr<FemImplicitDynamics> implicit_;
  std::vector<int32_t> grab_nodes_;  // scratch
  std::vector<double> grab_displacements_;
  std::vector<FemGrip> grips_;  // scratch
};

}  // namespace

std::unique_ptr<FemIntegrator> make_fem_implicit_integrator(const FemModel& model, const FemBoundaryConditions& supports,
                                                            const FemEngineOptions& options, Backend backend) {
  return std::make_unique<FemImplicitIntegrator>(model, supports, options, backend);
}

}  // namespace ctsurg::sim
