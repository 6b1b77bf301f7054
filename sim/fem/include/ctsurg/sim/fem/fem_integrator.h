// How the FEM engine advances its model in time: one integrator per file behind one interface, as
// NVIDIA Warp's warp/sim/integrator_*.py (each integrator owns how it steps; the engine owns the model,
// the supports, the tools' holds, the cuts, the removals and the surface). Three:
//
//   explicit  central differences at the critical step (fem_explicit_integrator.cpp over
//             fem_explicit_dynamics.h): grabs prescribed at each step's end, the probe and instruments
//             as contact, forces; CPU or CUDA.
//   implicit  backward Euler (fem_implicit_integrator.cpp over fem_implicit_dynamics.h): Newton per
//             step; grabs captured at their start within a step.
//   static    a quasi-static sequence (fem_static_integrator.cpp): each frame's equilibrium by the
//             linear model's condensed factorisation (fem_linear_static_solver.h), by Newton
//             (fem_static_solver.h), or by Newton in a region around the tools (fem_local_region.h).
//
// Warp's simulate(model, state_in, state_out, dt, control) is here advance(holds, tools, steps, u): the
// model is the engine's (the integrator keeps a reference), the state is the integrator's own (its
// solver's arrays; the engine keeps a displacement copy u), the control is the tools' holds
// (fem_tools.h), which each integrator applies its own way. A new integrator is one file with one
// class and a line in make_fem_integrator.
//
// Units: mm (local frame), s, g; forces uN, energies nJ.
#pragma once

#include "ctsurg/sim/base/backend.h"
#include "ctsurg/sim/base/real.h"
#include "ctsurg/sim/base/simulation_engine.h"
#include "ctsurg/sim/fem/fem_model.h"
#include "ctsurg/sim/fem/fem_static_solver.h"
#include "ctsurg/sim/fem/fem_tools.h"

#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

namespace ctsurg::sim {

struct FemEngineOptions;  // fem_engine.h
class FemContact;         // fem_contact.h
class FemLocalRegionSolver;  // fem_local_region.h

// One advance's outcome: stable or not (the dynamics' guard), and the Newton and CG iterations it took
// (0 for the explicit dynamics).
struct FemAdvance {
  StabilityReport stability;
  int newton_iterations = 0;
  int cg_iterations = 0;
  double solver_error_mm = NAN;  // a static quasi-Newton frame's FemStaticReport::error_estimate_mm, else NaN
};

// The state an integrator carries over a change of the mesh (a cut splitting nodes, a removal of
// elements): the explicit dynamics' raw displacements now and a step ago (#N x 3), the implicit
// dynamics' velocities (#N x 3 mm/s), the time and the steps taken. What an integrator does not use is
// empty or 0.
struct FemCarriedState {
  std::vector<Real> displacements, previous_displacements;
  std::vector<double> velocities;
  double time = 0;
  int64_t steps_taken = 0;
};

class FemIntegrator {
 public:
  virtual ~FemIntegrator() = default;

  // true: equilibrium() solves each frame; false: advance() steps in time.
  virtual bool quasi_static() const = 0;
  virtual double dt() const = 0;    // s (0 for the static sequence)
  virtual double time() const = 0;  // s: the state's time (the last frame solved, for the static sequence)

  // Dynamic: `steps` steps with `tools` acting through `holds`; u (#N x 3 mm) is the engine's copy of
  // the displacements, brought up to date when a tool captures nodes. An unstable report leaves the
  // state before the failing step.
  virtual FemAdvance advance(FemToolHolds& holds, const std::vector<ToolInput>& tools, int steps, std::vector<double>& u);
  // Static: the equilibrium at `time` under the tools' grabs and forces and gravity, into u, warm-started
  // from u when warm_start. Throws RuntimeError when it does not converge.
  virtual FemAdvance equilibrium(FemToolHolds& holds, const std::vector<ToolInput>& tools, double time, bool warm_start,
                                 std::vector<double>& u);

  // The displacements (#N x 3 mm) into u; the static sequence's are the engine's own (no-op).
  virtual void displacements(std::vector<double>& u) const = 0;
  virtual double kinetic_energy() const { return 0; }  // nJ
  // nJ at displacements u (the dynamics use their own state).
  virtual double strain_energy(const FemModel& model, const std::vector<double>& u) const = 0;

  // The state to carry over a change of the mesh, and its restoration on the integrator rebuilt for the
  // new mesh (u: the displacements, forces: the tools' nodal forces, empty when none act).
  virtual FemCarriedState carried_state() const = 0;
  virtual void restore(const FemCarriedState& state, const std::vector<double>& u, const std::vector<double>& forces) = 0;

  // The contact of the explicit dynamics, and the local region of the static sequence; nullptr otherwise.
  virtual const FemContact* contact() const { return nullptr; }
  virtual const FemLocalRegionSolver* local_region() const { return nullptr; }
  // The static sequence's last reactions (#N x 3 uN: what its held components needed, 0 elsewhere);
  // nullptr for the dynamics.
  virtual const std::vector<double>* reactions() const { return nullptr; }
};

// The integrator options.solver names (dynamic: explicit, implicit, static_equilibrium: static) over
// `model` with `supports`. The model is held by reference and must outlive the integrator. Throws as
// the solvers do (InputError(options.where, ...) for options or a backend they refuse, a static
// problem without supports, a local region whose supports do not hold the model).
std::unique_ptr<FemIntegrator> make_fem_integrator(const FemModel& model, const FemBoundaryConditions& supports,
                                                   const FemEngineOptions& options, Backend backend);

}  // namespace ctsurg::sim
