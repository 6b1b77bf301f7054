// The medial-atom chain in motion (vessel_chain.h): backward (implicit) Euler on the atoms' positions
// and the segments' orientations, each step a few Gauss-Newton iterations with a sparse direct solve.
//
// Why implicit and not XPBD. The chain is stiff in stretch (EA/l) and soft in bending (EI/l^3): for a
// 2 mm artery wall of 0.5 mm and atoms 1 mm apart the ratio is about 10^-1 to 10^-3, and the explicit
// critical step is microseconds. XPBD with Gauss-Seidel is stable at any step but only converges to
// the elastic energy's minimum after O(N^2) iterations for stretch and far more for bending, so a
// cantilever of 100 atoms would sag by a fraction of the true amount at a frame-rate step. Backward
// Euler minimises E(y) + |y - y_pred|^2_M / (2 dt^2) each step; Gauss-Newton on it (the Hessian
// J^T W J of the springs' strains, exact for small strains, plus M / dt^2) with one sparse LDL^T
// (Eigen's SimplicialLDLT, AMD ordering: a chain or tree factors in linear time with no fill beyond
// its 6-wide band) converges in 2-4 iterations, is stable at 1/60 s for any atom count, and its
// static limit (no inertia: solve_static) is exactly the energy's minimum: the cantilever matches
// Timoshenko's beam to discretisation error (tests/sim/vessel, docs/vessel.md).
//
// Unknowns: 3 per atom (position, mm) and 3 per segment (a rotation increment, world frame, rad:
// q <- exp(dtheta) q). Held unknowns (fixed atoms, a clamped segment = both its atoms fixed, atoms and
// segments a tool prescribes this step, cut segments) get identity rows: the pattern and its symbolic
// factorisation never change. Joint lengths: a joint's share of the rod counts only the halves of
// segments that are not held, so a clamp at atom 1 (atoms 0 and 1 fixed) is a built-in end of the
// elastic rod there (the cantilever's tip deflection then converges as 1/N^2, not 1/N).
//
// The Hessian leaves out the strains' second derivatives (geometric stiffness): Newton's iterations
// still converge to the true minimum (the gradient is exact), more slowly under large rotations or
// compression, and a buckling load is not predicted by the linearisation.
//
// Damping: mass-proportional, velocities scaled by 1 / (1 + alpha dt) after each step (backward Euler
// adds its own numerical damping, of order omega dt per step).
//
// Units: mm, s, g: forces uN, torques uN mm, energies nJ.
#pragma once

#include "ctsurg/sim/vessel/vessel_chain.h"

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

namespace ctsurg::sim {

struct VesselDynamicsOptions {
  double dt = 1.0 / 60;                     // s (> 0)
  double mass_damping = 0;                  // alpha, 1/s (>= 0)
  std::array<double, 3> gravity{0, 0, 0};   // mm/s^2
  int max_newton_iterations = 6;            // per step (>= 1)
  double tolerance_mm = 1e-6;               // stop when no position moves more (rotations: x 1 mm)
};

class VesselDynamics {
 public:
  // The chain must outlive this object. State: the rest positions and frames, at rest.
  VesselDynamics(const VesselChain& chain, const VesselDynamicsOptions& options);
  ~VesselDynamics();
  VesselDynamics(const VesselDynamics&) = delete;
  VesselDynamics& operator=(const VesselDynamics&) = delete;

  const VesselChain& chain() const { return chain_; }
  const VesselDynamicsOptions& options() const { return options_; }
  void set_dt(double dt) { options_.dt = dt; }

  // State: positions #A x 3 mm, velocities #A x 3 mm/s, frames #S, angular velocities #S x 3 rad/s.
  std::vector<double> x, v;
  std::vector<Quaternion> q;
  std::vector<double> w;
  // Loads for the next step or static solve: forces on atoms (#A x 3, uN; gravity is added) and
  // torques on segments (#S x 3, uN mm), both kept until changed.
  std::vector<double> force, torque;

  // Fixed for good (ids into atoms): a segment whose two atoms are fixed is clamped (its frame held).
  void fix_atoms(const std::vector<int32_t>& atoms);
  bool atom_fixed(int32_t a) const { return fixed_atom_[static_cast<size_t>(a)] != 0; }
  // Held for the next step only: atoms at a position, segments at a frame.
  void prescribe_atom(int32_t a, const Vec3& position_mm);
  void prescribe_segment(int32_t s, const Quaternion& frame);
  void clear_prescribed();
  // Removes a segment's stretch-shear spring and its joints (a cut): the chain splits at it.
  void cut_segment(int32_t s);
  bool segment_alive(int32_t s) const { return alive_[static_cast<size_t>(s)] != 0; }

  // One backward Euler step of dt; returns the Gauss-Newton iterations taken.
  int step();
  // The static equilibrium under the loads (no inertia), from the current state: Newton until the
  // update is below tolerance_mm or max_iterations; returns the iterations taken. The model must be
  // held against rigid motion (fixed atoms).
  int solve_static(int max_iterations);

  double elastic_energy() const;  // nJ
  double kinetic_energy() const;  // nJ

 private:
  struct Solver;
  double assemble(bool inertia, const std::vector<double>& x_pred, const std::vector<Quaternion>& q_pred, bool with_matrix);
  bool held_segment(size_t s) const;
  int newton(bool inertia, const std::vector<double>& x_pred, const std::vector<Quaternion>& q_pred, int max_iterations);

  const VesselChain& chain_;
  VesselDynamicsOptions options_;
  std::vector<uint8_t> fixed_atom_, fixed_segment_, alive_;
  std::vector<uint8_t> prescribed_atom_, prescribed_segment_;
  std::vector<double> prescribed_x_;
  std::vector<Quaternion> prescribed_q_;
  std::unique_ptr<Solver> solver_;
};

}  // namespace ctsurg::sim
