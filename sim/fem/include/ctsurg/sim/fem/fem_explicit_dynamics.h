// Explicit dynamics of a FemModel: central differences with a lumped mass matrix and Rayleigh mass
// damping D = lambda_d M (Huang et al., the FEM paper, eq. 11-12; with a diagonal M and D each step is
// explicit: only the internal force R(a) is recomputed). Total Lagrangian element forces
// (fem_element_impl.h) are computed per element in float (Real), then gathered per node through the
// model's node -> (element, corner) CSR: no atomics, bit-identical for any thread count.
//
// State: displacements u (#N x 3, Real, mm) at t and t - dt. Positions are rest + u (double).
// Tools: fixed nodes; prescribed displacement of a node set (a grab: u held at given values, moved
// between steps by the caller); sphere contact (a probe: nodes inside the sphere projected to its
// surface after each step); gravity; external nodal forces.
//
// Critical step (fem_critical_time_step): the CFL limit of the smallest element,
//   dt_crit = min_e h_e / c,   h_e = 3 V_e / (largest face area) (the tet's smallest altitude),
//   c = sqrt((lambda + 2 mu) / rho) (dilatational wave speed, small strain),
// and dt = safety_factor dt_crit. Large compressions stiffen Neo-Hookean and StVK material, so keep a
// margin (default 0.5).
//
// Stability guard (checked every step for inversion and non-finite values, every energy_check_interval
// steps for energy growth): an inverted element (det F <= 0), a non-finite displacement, or kinetic
// energy growing by more than energy_growth between checks (from above energy_floor) throws
// RuntimeError naming the time, the element or node, its rest position, and a suggested step. The step
// that would break is not applied: the state stays finite.
//
// Backends. cpu: OpenMP over elements, then nodes (`threads`). cuda: the state (displacements, corner
// forces, masses, element and node data, tools) lives on CUDA device 0 for the object's life and step(n)
// runs the same per-element and per-node kernels there (src/fem_device_dynamics.h), waiting for the
// device once per call; the guard is checked on the device with the same rule, rollback and messages
// (an inverted element or non-finite node leaves the state before the failing step, exactly as on the
// CPU). Accessors download on request. `threads` is ignored. In a build without CUDA, or without a
// device, asking for cuda is InputError("fem dynamics", "backend", ...).
//
// Units: mm, g, s; forces uN, energies nJ, damping 1/s, gravity mm/s^2.
#pragma once

#include "ctsurg/sim/base/backend.h"
#include "ctsurg/sim/base/instrument.h"
#include "ctsurg/sim/base/real.h"
#include "ctsurg/sim/fem/fem_contact.h"
#include "ctsurg/sim/fem/fem_model.h"

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

namespace ctsurg::sim {

class FemDeviceDynamics;  // src/fem_device_dynamics.h: the Backend::cuda state (no CUDA types here)

struct FemCriticalStep {
  double critical = 0;        // s, min_e h_e / c_e (c_e: the dilatational wave speed of e's material)
  double safety_factor = 0.5;
  double dt = 0;              // s, safety_factor * critical
  int32_t element = -1;       // the element that sets it
  double length = 0;          // mm, its h_e
  double wave_speed = 0;      // mm/s, its c_e
};

// Throws InputError("fem critical step", "safety_factor", ...) unless 0 < safety_factor <= 1.
FemCriticalStep fem_critical_time_step(const FemModel& model, double safety_factor = 0.5);

struct FemDynamicsOptions {
  double dt = 0;                          // s; 0 = fem_critical_time_step(model, safety_factor).dt
  double safety_factor = 0.5;             // for the automatic step
  double mass_damping = 0;                // lambda_d, 1/s (>= 0): D = lambda_d M, eq. 12
  std::array<double, 3> gravity{0, 0, 0};  // mm/s^2
  int energy_check_interval = 16;         // steps between kinetic-energy checks (>= 1)
  double energy_growth = 100;             // largest ratio of kinetic energies between checks
  double energy_floor = 1e-6;             // nJ; growth from below this is not counted
  int threads = 0;                        // 0 = one per 8,192 elements up to OpenMP's default
  FemContactOptions contact;              // bodies and self-contact after each step (fem_contact.h; cpu)
};

class FemExplicitDynamics {
 public:
  // Throws InputError("fem dynamics", field, ...) for a backend that cannot run here ("backend"),
  // options out of range, or a dt above the critical step (field "dt"). The model must outlive this
  // object. Starts at rest (u = 0).
  FemExplicitDynamics(const FemModel& model, const FemDynamicsOptions& options = {}, Backend backend = Backend::cpu);
  ~FemExplicitDynamics();
  FemExplicitDynamics(FemExplicitDynamics&&) noexcept;
  FemExplicitDynamics(const FemExplicitDynamics&) = delete;
  FemExplicitDynamics& operator=(const FemExplicitDynamics&) = delete;

  // Holds `nodes` at zero displacement (replaces the previous fixed set).
  void set_fixed_nodes(const std::vector<int32_t>& nodes);
  // Holds `nodes` at `displacements` (#G x 3 mm) from the next step on (a grab; call again to move it;
  // the displacement jumps there, so move by small increments). Replaces the previous grab.
  void set_prescribed(const std::vector<int32_t>& nodes, const std::vector<double>& displacements);
  void clear_prescribed();
  // External nodal forces, #N x 3 uN (empty = none).
  void set_external_forces(const std::vector<double>& forces);
  // A rigid sphere (centre LPS mm, radius mm) that free nodes may not enter; radius 0 = none.
  void set_contact_sphere(const std::array<double, 3>& centre, double radius);
  // Rigid instruments at their poses (base/instrument.h): free nodes inside one are projected out of
  // it after each step, as the sphere's; empty = none. The views' grids must outlive the steps. cpu
  // only (InputError on cuda).
  void set_contact_instruments(const std::vector<InstrumentView>& instruments);

  // Advances `steps` steps of dt. Throws RuntimeError (the stability guard above).
  void step(int steps = 1);

  double time() const { return time_; }            // s
  double dt() const { return dt_; }                // s
  int64_t steps_taken() const { return steps_; }
  int64_t contacts() const { return contacts_; }   // nodes moved by the sphere and instruments, and contact pairs, in the last step
  const FemContact* contact() const { return contact_.get(); }  // null unless options.contact.enabled
  std::vector<double> displacements() const;       // #N x 3 mm
  std::vector<double> positions() const;           // #N x 3 LPS mm, rest + u
  std::vector<Real> raw_displacements() const;     // #N x 3 mm, Real (the step's own values)
  std::vector<Real> raw_previous_displacements() const;  // #N x 3 mm, Real: u one step ago (cpu)
  // Continues from a state (u and u one step ago, #N x 3 mm; the clock and step count): after the
  // model changed under a copy of it (a cut: fem_cutting.h). cpu only (InputError on cuda or a size
  // mismatch).
  void restore_state(const std::vector<Real>& u, const std::vector<Real>& u_prev, double time, int64_t steps);
  // Kinetic energy sum_i m_i |u_i(t) - u_i(t - dt)|^2 / (2 dt^2), nJ (backward-difference velocity;
  // cuda: the guard's device sum, whose order of additions differs from the CPU's serial sum).
  double kinetic_energy() const;
  double strain_energy() const;                    // nJ (fem_strain_energy)
  // The nodal internal forces of the current state as the step computes them (float), #N x 3 uN.
  std::vector<Real> internal_forces();

 private:
  void update_inverse_mass();
  void step_on_device(int steps);

  const FemModel& model_;
  FemDynamicsOptions options_;
  double dt_ = 0, time_ = 0, last_energy_ = -1;
  int64_t steps_ = 0, contacts_ = 0;
  std::vector<Real> dm_inverse_, volume_;          // Real copies of the model's element data
  std::vector<Real> u_, u_prev_, u_next_, corner_forces_;  // cpu: the state (empty for cuda)
  std::vector<Real> inv_mass_, external_;
  std::vector<uint8_t> fixed_;
  std::vector<int32_t> prescribed_nodes_;
  std::vector<Real> prescribed_;
  std::array<double, 4> sphere_{0, 0, 0, 0};
  std::vector<InstrumentView> instruments_;
  std::unique_ptr<FemContact> contact_;  // when options.contact.enabled
  std::unique_ptr<FemDeviceDynamics> device_;  // cuda: the state on the device; null for cpu
};

}  // namespace ctsurg::sim
