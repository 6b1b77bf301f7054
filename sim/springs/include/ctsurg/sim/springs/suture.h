// Stitches for the spring models: a suture joins pairs of particles across an incision with extra
// springs whose rest length shrinks from the pair's distance when the stitch is placed to a target
// (the knot tightened) over a time window, then stays at the target (the knot holds); the tissue's own
// springs carry the pull into the lips. Huang et al., "Virtual Surgery Deformable Modelling Employing
// GPU Based Computation" (the FEM paper of docs/fem.md) show cutting and suturing (fig. 12) but give no
// method; a stitch as a spring between the two lips' nodes is the simplest model that closes a wound.
//
// Each stitch end attaches to the particle nearest to its point at rest (lowest id on ties): points are
// given on the rest anatomy, as every other position of a scenario, so the stitch joins the same
// tissue however far a retractor has pulled it when the suture starts.
// A stitch is a Hooke spring (the same law as the model's: spring_forces_impl.h, without damping)
//
//     d = x_b - x_a,  f_a = k (|d| - L(t)) d / |d|,  f_b = -f_a,
//     L(t) = L0 + (target - L0) clamp((t - start) / (end - start), 0, 1),
//
// added to the Verlet update after the step as f / m dt^2 (the force tool's update, spring_engine.h).
//
// Stability. A stitch of stiffness k raises particle i's spring sum K_i to K_i + k; the explicit step
// stays stable while dt <= sqrt(2) sqrt(m_i / (K_i + k)) for every stitched particle (the Gershgorin
// bound of stability.h: the coupled network's critical step is at least dt_crit / sqrt 2, dt_crit =
// 2 sqrt(m / K)). stitch_step_limit gives that step; the engine refuses a stitch that breaks it.
//
// Units: mm (the engine's local frame), s, g; stiffness g/s^2 (= uN/mm).
#pragma once

#include "ctsurg/sim/base/particle_state.h"
#include "ctsurg/sim/base/simulation_engine.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace ctsurg::sim {

// Bounds of a stitch (docs/sim.md, "Suturing").
inline constexpr double kMaxStitchLengthMm = 30;   // a stitch's ends at most this far apart when placed
inline constexpr double kStitchSnapCells = 3;      // a stitch point at most this many springs from a particle

struct Stitch {
  int32_t a = -1, b = -1;        // particle ids, a != b
  double initial_length = 0;     // mm, |x_b - x_a| when placed
  Vec3 offset_a{0, 0, 0};        // mm, the stitch point minus particle a at rest (the point drawn on
  Vec3 offset_b{0, 0, 0};        //   the surface moves with its particle)
};

// The stitch's rest length at time t (s): L0 -> target over [start_s, end_s] (end_s > start_s), linear.
double stitch_rest_length(double initial_mm, double target_mm, double start_s, double end_s, double t);

// Attaches each stitch (points[k] = {a, b}, mm, local frame) to the particles nearest to a and b at rest
// (`rest`: #P x 3 mm, local frame); its initial length is their distance in `state` (now). `fields[k]`
// names stitch k in messages, `where` the scenario file. max_snap_mm: the farthest a point may be from
// its particle. InputError(where, fields[k] + ".a" or ".b", ...) for a point farther than that;
// InputError(where, fields[k], ...) when both ends attach to the same particle or the particles are
// farther apart than kMaxStitchLengthMm now.
std::vector<Stitch> attach_stitches(const std::vector<std::array<Vec3, 2>>& points, const std::vector<std::string>& fields,
                                    const std::vector<Real>& rest, const ParticleState& state, double max_snap_mm,
                                    const std::string& where);

// The largest step (s) at which particle i, of mass m (g) and spring sum K (g/s^2), stays stable with
// an added stitch stiffness k (g/s^2): sqrt(2) sqrt(m / (K + k)). +inf for m <= 0 (a fixed particle).
double stitch_step_limit(double mass, double spring_sum, double stitch_stiffness);

// How a suture's stitches tighten: each stitch's rest length goes from its initial length to target_mm
// over [start_s, end_s] (s, end_s > start_s); stiffness g/s^2 per stitch.
struct SutureSchedule {
  double start_s = 0, end_s = 1;
  double target_mm = 0;
  double stiffness = 0;
};

// Adds each stitch's force at time t (s) to the Verlet update of its free ends: x += f / m dt^2 (dt s;
// fixed particles stay). Returns the largest |(|d| - L(t))| over the stitches (mm).
double apply_stitches(ParticleState& state, const std::vector<Stitch>& stitches, const SutureSchedule& schedule, double t, double dt);

}  // namespace ctsurg::sim
