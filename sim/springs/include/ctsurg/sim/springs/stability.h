// Stability of the explicit (Verlet) integration: the critical time step, energies, and a guard that
// stops a run before a trajectory holds an exploded or non-finite state.
//
// Critical step. For one mass m on springs of total stiffness K, Verlet is stable for
// dt < 2 / omega = 2 sqrt(m / K). Over a network, dt_crit = min over particles of 2 sqrt(m_i / K_i),
// K_i = sum of the stiffnesses of particle i's present springs. This per-particle estimate is not a
// bound for the coupled system: by Gershgorin's theorem the largest eigenvalue of M^-1 K is at most
// max_i 2 K_i / m_i (uniform masses), i.e. the true critical step is >= sqrt(2 m / K), i.e.
// >= dt_crit / sqrt(2). The default safety factor 0.5 (dt = 0.5 dt_crit = sqrt(m / K)) stays below
// that bound with a margin of 1/sqrt(2); spring damping c adds c / m to the stiffness-like terms and is
// not included (keep damping << sqrt(K m)).
//
// Units: see particle_state.h (mm, s, g; energies in nJ = g mm^2/s^2).
#pragma once

#include "ctsurg/sim/base/particle_state.h"
#include "ctsurg/sim/base/stability_report.h"
#include "ctsurg/sim/springs/explicit_spring_model.h"
#include "ctsurg/sim/springs/spring_grid_model.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace ctsurg::sim {

constexpr double kDefaultSafetyFactor = 0.5;

struct CriticalStep {
  double critical = 0;        // s, min_i 2 sqrt(m_i / K_i)
  double safety_factor = kDefaultSafetyFactor;
  double dt = 0;              // s, safety_factor * critical: the "auto" step
  int32_t particle = -1;      // the particle that sets it
  double mass = 0;            // g, its mass
  double stiffness_sum = 0;   // g/s^2, its K_i
};

// Throws InputError("stability", "safety_factor", ...) unless 0 < safety_factor <= 1, and
// InputError("stability", "springs", ...) when no particle has a spring.
CriticalStep critical_time_step(const SpringGridModel& model, double safety_factor = kDefaultSafetyFactor);
CriticalStep critical_time_step(const ExplicitSpringModel& model, double safety_factor = kDefaultSafetyFactor);

// Kinetic energy sum_i m_i |x_i - px_i|^2 / (2 dt^2), nJ, with the Verlet velocity (x - px) / dt.
double kinetic_energy(const ParticleState& state, double dt);
// Elastic energy sum over present springs of k (|x_i - x_j| - l)^2 / 2, nJ (each spring once).
double spring_energy(const SpringGridModel& model, const ParticleState& state);
double spring_energy(const ExplicitSpringModel& model, const ParticleState& state);
// Total momentum sum_i m_i (x_i - px_i) / dt, g mm/s.
std::array<double, 3> momentum(const ParticleState& state, double dt);

struct StabilityGuardOptions {
  double max_step_mm = 0;        // largest move of a particle in one step, mm; 0 = half the shortest
                                 // rest length (a stable run near dt_crit moves far less)
  double energy_growth = 100;    // largest kinetic-energy ratio between consecutive checks
  double energy_floor = 1e-6;    // nJ; growth from below this is not counted (a body at rest)
  double gravity = 0;            // mm/s^2, |g| of the run: a piece cut free falls, and by time t it may
                                 // move g t dt per step without being unstable; the step limit grows by that
};

// Watches a run: non-finite positions, a particle moving more than max_step_mm in a step, and
// kinetic-energy growth by more than energy_growth between checks.
class StabilityGuard {
 public:
  // rest_positions #P x 3 LPS mm (the model's, to name where the trouble is); shortest_rest_length mm;
  // dt s, the step of the run.
  StabilityGuard(std::vector<Real> rest_positions, double shortest_rest_length, double dt,
                 const StabilityGuardOptions& options = {});
  // Checks the state at `time` (s). Deterministic (lowest offending id), parallel over particles.
  // external_work: tools moved particles since the last check (a probe or grab does work on the
  // system, so energy growth is expected); only the non-finite and step-size tests apply then.
  StabilityReport check(const ParticleState& state, double time, bool external_work = false);
  // check(), then throws RuntimeError(report.message) when unstable.
  void enforce(const ParticleState& state, double time);

 private:
  std::vector<Real> rest_;
  double dt_, max_step_;
  StabilityGuardOptions options_;
  double last_energy_ = -1;
};

// The guard for a model (its rest positions and shortest rest length).
StabilityGuard make_stability_guard(const SpringGridModel& model, double dt, const StabilityGuardOptions& options = {});
StabilityGuard make_stability_guard(const ExplicitSpringModel& model, double dt, const StabilityGuardOptions& options = {});

}  // namespace ctsurg::sim
