// Spherical interaction tools at the model level (Mosegaard & Sorensen 2005, section 2.7):
//  - probe: particles inside the sphere are projected onto its surface (along the ray from the
//    centre; a particle exactly at the centre goes to centre + (0, 0, r)); fixed particles stay;
//  - grab: the free particles inside the sphere at grab time are captured with their offsets from
//    the centre (fixed particles stay fixed, as the FEM's grabs leave fixed nodes alone); while grabbed, apply_grab() after each step sets them to centre + offset (overriding the
//    integration, as the papers do), and their neighbours follow through the springs.
// Per-particle kernels: src/sphere_tools_impl.h. Units: LPS mm.
#pragma once

#include "ctsurg/sim/base/particle_state.h"
#include "ctsurg/sim/base/tool_shapes.h"

#include <array>
#include <cstdint>
#include <vector>

namespace ctsurg::sim {

struct Grab {
  std::vector<int32_t> particles;  // #G captured particle ids, increasing
  std::vector<Real> offsets;       // #G x 3, position - centre at grab time, mm
};

// The free particles (inv_mass > 0) strictly inside the sphere (current positions) and their offsets. Throws
// InputError("grab", "radius", ...) unless the radius is finite and > 0.
Grab grab_particles_in_sphere(const ParticleState& state, const Sphere& tool, int threads = 0);
// Sets every grabbed particle's current position to centre + offset (LPS mm).
void apply_grab(ParticleState& state, const Grab& grab, const std::array<double, 3>& centre, int threads = 0);
// Projects the free particles inside the sphere onto its surface; returns how many moved.
int64_t probe_sphere(ParticleState& state, const Sphere& tool, int threads = 0);

}  // namespace ctsurg::sim
