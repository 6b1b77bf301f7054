// The explicit integrator (fem_integrator.h): central differences at the critical step
// (fem_explicit_dynamics.h). Before every batch of steps: the grabs prescribed at the step's end, the
// first active probe as the dynamics' contact sphere, the active instruments as contact shapes, the
// forces when they changed. A failing step (the dynamics' guard) is reported unstable, not thrown.
#include "ctsurg/core/error.h"
#include "ctsurg/sim/base/instrument.h"
#include "ctsurg/sim/fem/fem_engine.h"
#include "ctsurg/sim/fem/fem_explicit_dynamics.h"
#include "fem_integrators.h"

#include <array>
#include <optional>

namespace ctsurg::sim {
namespace {

class FemExplicitIntegrator final : public FemIntegrator {
 public:
  FemExplicitIntegrator(const FemModel& model, const FemBoundaryConditions& supports, const FemEngineOptions& options, Backend backend)
      : where_(options.where) {
    FemDynamicsOptions o;  // the explicit dynamics' own options struct: every field it needs, from the engine's
    o.dt = options.dt;
    o.safety_factor = options.safety_factor;
    o.mass_damping = options.mass_damping;
    o.gravity = options.gravity;
    o.threads = options.threads;
    o.contact = options.contact;
    dynamics_.emplace(model, o, backend);
    dynamics_->set_fixed_nodes(supports.fixed_nodes);
  }

  bool quasi_static() const override { return false; }
  double dt() const override { return dynamics_->dt(); }
  double time() const override { return dynamics_->time(); }

  FemAdvance advance(FemToolHolds& holds, const std::vector<ToolInput>& tools, int steps, std::vector<double>& u) override {
    const double t_next = dynamics_->time() + dynamics_->dt();
    if (holds.captures(tools)) displacements(u);  // a tool captures the nodes where they are now
    holds.update_grabs(tools, t_next, u, false, grab_nodes_, grab_displacements_);
    if (!grab_nodes_.empty()) {
      dynamics_->set_prescribed(grab_nodes_, grab_displacements_);
      had_grab_ = true;
    } else if (had_grab_) {
      dynamics_->clear_prescribed();
      had_grab_ = false;
    }
    // One probe at a time is supported by the dynamics' contact sphere: the first active one.
    std::array<double, 3> centre{0, 0, 0};
    double radius = 0;
    for (const ToolInput& tool : tools) {
      if (tool.acts == ToolPrimitive::push_sphere && tool.active) {
        centre = tool.centre;
        radius = tool.radius_mm;
        break;
      }
    }
    dynamics_->set_contact_sphere(centre, radius);
    instrument_views_.clear();
    for (const ToolInput& tool : tools) {
      if (tool.acts != ToolPrimitive::push_shape || !tool.active) continue;
      if (!tool.instrument) throw InputError(where_, tool.label, "the instrument has no shape");
      instrument_views_.push_back(instrument_view(*tool.instrument, tool.orientation, tool.centre));
    }
    dynamics_->set_contact_instruments(instrument_views_);
    if (holds.update_forces(tools, u, false)) dynamics_->set_external_forces(holds.nodal_forces());
    FemAdvance a;
    try {
      dynamics_->step(steps);
    } catch (const RuntimeError& e) {
      a.stability.stable = false;
      a.stability.time = dynamics_->time();
      a.stability.message = e.what();
    }
    return a;
  }

  void displacements(std::vector<double>& u) const override {
    const auto d = dynamics_->displacements();
    u.assign(d.begin(), d.end());
  }
  double kinetic_energy() const override { return dynamics_->kinetic_energy(); }
  double strain_energy(const FemModel&, const std::vector<double>&) const override { return dynamics_->strain_energy(); }

  FemCarriedState carried_state() const override {
    FemCarriedState s;
    s.displacements = dynamics_->raw_displacements();
    s.previous_displacements = dynamics_->raw_previous_displacements();
    s.time = dynamics_->time();
    s.steps_taken = dynamics_->steps_taken();
    return s;
  }
  void restore(const FemCarriedState& s, const std::vector<double>&, const std::vector<double>& forces) override {
    dynamics_->restore_state(s.displacements, s.previous_displacements, s.time, s.steps_taken);
    if (!forces.empty()) dynamics_->set_external_forces(forces);
    had_grab_ = false;
  }
  const FemContact* contact() const override { return dynamics_->contact(); }

 private:
  std::string where_;
  std::optional<FemExplicitDynamics> dynamics_;
  bool had_grab_ = false;
  std::vector<int32_t> grab_nodes_;  // scratch
  std::vector<double> grab_displacements_;
  std::vector<InstrumentView> instrument_views_;  // the active instruments at the last step
};

}  // namespace

std::unique_ptr<FemIntegrator> make_fem_explicit_integrator(const FemModel& model, const FemBoundaryConditions& supports,
                                                            const FemEngineOptions& options, Backend backend) {
  return std::make_unique<FemExplicitIntegrator>(model, supports, options, backend);
}

}  // namespace ctsurg::sim
