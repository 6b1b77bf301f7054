// Implicit dynamics of a FemModel, for every material law: steps of a frame (1/60 s) on stiff tissue,
// where the explicit dynamics' critical step is tens of microseconds (fem_explicit_dynamics.h). Two
// schemes (options.scheme): backward Euler, which damps every mode by its step, and the implicit
// midpoint rule, which keeps the motion and leaves the damping to the tissue's Rayleigh constants.
//
// Backward Euler:
// With lumped masses M, Rayleigh damping D = alpha M + beta K_n (K_n the tangent at the step's start)
// and v = (u_{n+1} - u_n) / h, each step solves
//
//   M (u - u_n - h v_n) / h^2 + D (u - u_n) / h = f_int(u) + f_ext          for u = u_{n+1}
//
// by Newton on the factorised tangent K(u) + (1/h^2 + alpha/h) M + (beta/h) K_n (src/fem_newton.h: the
// static solver's machinery, with its direct solves, factor reuse and tangent projection), from the
// predictor u_n + h v_n. Backward Euler is unconditionally stable for the linear law and damps: a mode of
// angular frequency w loses a factor 1 / (1 + (w h)^2)^(1/2) of its amplitude per step even with no
// Rayleigh damping (Hairer and Wanner, Solving ODEs II, section IV.2), so the high modes of a mesh are gone
// in a step and the lowest ones decay too: energy is not conserved (docs/fem.md measures it).
//
// Implicit midpoint (Hairer, Lubich and Wanner, Geometric Numerical Integration, section VI.3; for the
// linear law the same as Newmark's average acceleration, beta 1/4, gamma 1/2): with w = (u_n + u_{n+1})/2,
//
//   M (v_{n+1} - v_n) / h = f_int~(w) + f_ext - D (v_n + v_{n+1}) / 2,   u_{n+1} - u_n = h (v_n + v_{n+1}) / 2,
//
// solved for w by the same Newton as the static problem: c_m = 4/h^2 + 2 alpha/h, c_m y = 4/h^2 (u_n +
// h v_n / 2) + 2 alpha/h u_n, c_b = 2 beta / h. f_int~ is each element's discrete gradient between u_n and
// u_{n+1} (Gonzalez 1996; src/fem_newton.h), so f_int~ . (u_{n+1} - u_n) = -(E(u_{n+1}) - E(u_n)) exactly
// and the step changes the energy by exactly -h v_mid . D v_mid <= 0: it never grows, and without
// Rayleigh damping it is kept, for every law (the plain midpoint rule doubled a Neo-Hookean beam's energy
// within a second, tests/sim/fem/test_fem_implicit_dynamics.cpp). A-stable, no mode damped by the step;
// a mode's frequency is off by about (w h)^2 / 12 (-0.33 % for a 1.9 Hz bar at 1/60 s: measured), and its
// decay is the set Rayleigh ratio zeta = alpha / (2 w) + beta w / 2 (0.0497 for 0.05 set; backward Euler
// adds 0.10 of its own). High modes a grab excites ring until the stiffness damping beta takes them.
// Newton's tangent carries the discrete gradient's leading term (its positive part), and its line search
// is non-monotone (no potential): a step converges in a few more iterations than backward Euler's.
//
// Tools: fixed nodes; prescribed displacements of a node set (a grab, at the step's end); external nodal
// forces; gravity. No contact sphere (probes run on the explicit dynamics).
//
// Convergence of a step: options.newton's rule (tolerance_mm, default 1e-4 mm here: a step's inertia
// term makes the static relative rule meaningless). A step whose Newton fails is retried as two half
// steps (a grab moving in equal parts over them), down to max_halvings; then RuntimeError naming the
// time and the cause, the state as it was before the step.
//
// Backends: cpu; cuda runs the linear solves' conjugate gradients on the device when the solve is
// iterative (the direct factorisation stays on the CPU).
//
// Units: mm, g, s; forces uN, energies nJ, alpha 1/s, beta s, gravity mm/s^2.
#pragma once

#include "ctsurg/sim/base/backend.h"
#include "ctsurg/sim/fem/fem_grip.h"
#include "ctsurg/sim/fem/fem_model.h"
#include "ctsurg/sim/fem/fem_static_solver.h"

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

namespace ctsurg::sim {

enum class FemImplicitScheme { backward_euler, midpoint };

struct FemImplicitOptions {
  double dt = 1.0 / 60;                   // s (> 0)
  FemImplicitScheme scheme = FemImplicitScheme::backward_euler;  // see above
  double mass_damping = 0;                // alpha, 1/s (>= 0)
  double stiffness_damping = 0;           // beta, s (>= 0)
  std::array<double, 3> gravity{0, 0, 0};  // mm/s^2
  int max_halvings = 6;                   // a failed step is retried as 2, 4, ... sub-steps
  int threads = 0;                        // 0 = one per 8,192 elements up to OpenMP's default
  FemStaticOptions newton;                // the Newton solves (tolerance_mm 0 = 1e-4 mm)
};

struct FemImplicitStepReport {
  int newton_iterations = 0;   // over the step's sub-steps
  int quasi_newton_iterations = 0;  // newton.nonlinear quasi_newton: L-BFGS iterations over the sub-steps
  int factorizations = 0;
  int substeps = 1;            // 2^halvings
  double seconds = 0;
};

class FemNewton;
class DeviceConjugateGradient;

class FemImplicitDynamics {
 public:
  // Throws InputError("fem implicit", field, ...) for options out of range or a backend that cannot run
  // here. The model must outlive this object. Starts at rest (u = 0, v = 0).
  FemImplicitDynamics(const FemModel& model, const FemImplicitOptions& options = {}, Backend backend = Backend::cpu);
  ~FemImplicitDynamics();
  FemImplicitDynamics(const FemImplicitDynamics&) = delete;
  FemImplicitDynamics& operator=(const FemImplicitDynamics&) = delete;

  // Holds `nodes` at zero displacement, and the single components `components` (3 node + axis: rollers,
  // symmetry planes). Replaces the previous supports.
  void set_supports(const std::vector<int32_t>& nodes, const std::vector<int32_t>& components = {});
  // Holds `nodes` at `displacements` (#G x 3 mm) at the end of the next steps (a grab). Replaces the
  // previous grab.
  void set_prescribed(const std::vector<int32_t>& nodes, const std::vector<double>& displacements);
  void clear_prescribed();
  // The volume grips (fem_grip.h) at the next step's end. A grip with the same elements as the last
  // step's moves from its last target to this one over the step (sub-steps in equal parts; the midpoint
  // scheme pulls w to the targets' mean over the step); a new one starts at its target.
  void set_grips(std::vector<FemGrip> grips);
  // External nodal forces, #N x 3 uN (empty = none).
  void set_external_forces(const std::vector<double>& forces);

  // Advances `steps` steps of dt. Throws RuntimeError when a step fails after max_halvings halvings (the
  // state stays as before that step).
  FemImplicitStepReport step(int steps = 1);

  double time() const { return time_; }
  double dt() const { return options_.dt; }
  int64_t steps_taken() const { return steps_; }
  const std::vector<double>& displacements() const { return u_; }  // #N x 3 mm
  const std::vector<double>& velocities() const { return v_; }     // #N x 3 mm/s
  double kinetic_energy() const;   // sum_i m_i |v_i|^2 / 2, nJ
  // Continues from a state (u mm and v mm/s, #N x 3; the clock and step count): after the model changed
  // under a copy of it (a cut: fem_cutting.h). InputError on a size mismatch or a non-finite value.
  void restore_state(const std::vector<double>& u, const std::vector<double>& v, double time, int64_t steps);
  double strain_energy() const;    // nJ (fem_strain_energy)

 private:
  bool advance(double h, const std::vector<double>& start, double fraction, FemImplicitStepReport& report, std::string& failure);

  const FemModel& model_;
  FemImplicitOptions options_;
  std::unique_ptr<DeviceConjugateGradient> device_cg_;
  std::unique_ptr<FemNewton> newton_;
  std::vector<uint8_t> fixed_;                 // #N x 3 components held at 0
  std::vector<int32_t> prescribed_nodes_;
  std::vector<double> prescribed_;             // #G x 3
  std::vector<FemGrip> grips_;                 // at the step's end (set_grips)
  std::vector<std::vector<double>> grip_start_;  // each grip's target at the step's start
  std::vector<double> external_;               // #N x 3 forces + weight
  std::vector<double> forces_;                 // #N x 3 (set_external_forces)
  std::vector<double> u_, v_;
  double time_ = 0;
  int64_t steps_ = 0;
};

}  // namespace ctsurg::sim
