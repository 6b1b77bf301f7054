// Removing tissue from a spring model (the remove primitive: a cautery, base/simulation_engine.h): the
// particles inside a sphere, nearest its centre first, as long as a volume budget lasts. A removed
// particle loses every spring it had (grid: both particles' bits; explicit: the alive flag and the CPU
// layout's entries, through cut_explicit_spring), is frozen where it is (inverse mass 0, no velocity:
// nothing captures, pushes or loads it any more) and counts as gone; the surface over it is opened and
// closed by its owner (embedded_surface.h).
//
// A particle's volume is its mass over the tissue's density (mm^3): a grid cell's volume, its occupied
// fraction with mass_from_fraction; a tet mesh node's lumped share of its tets.
//
// Units: mm, g, g/mm^3; positions in the state's frame.
#pragma once

#include "ctsurg/sim/base/particle_state.h"
#include "ctsurg/sim/base/tool_shapes.h"
#include "ctsurg/sim/springs/explicit_spring_model.h"
#include "ctsurg/sim/springs/spring_grid_model.h"

#include <cstdint>
#include <vector>

namespace ctsurg::sim {

struct RemovalResult {
  std::vector<int32_t> particles;  // removed now, in the order taken (nearest the centre first)
  double volume_mm3 = 0;           // their volume
  int64_t springs = 0;             // springs they took with them (each counted once)
  bool exhausted = false;          // no tissue left in the sphere: the budget has nothing to spend on
};

// Removes the present particles (removed[i] == 0, inverse mass > 0) strictly inside `sphere` at their
// current positions, nearest first (lower id on ties), while the next one's volume fits in
// *budget_mm3, which is spent. removed (#P) marks them. density > 0 (g/mm^3). InputError("cautery", ...)
// for a state or mask of the wrong size or a density that is not positive.
RemovalResult remove_particles_in_sphere(SpringGridModel& model, ParticleState& state, std::vector<uint8_t>& removed,
                                         const Sphere& sphere, double density, double* budget_mm3);
RemovalResult remove_particles_in_sphere(ExplicitSpringModel& model, ParticleState& state, std::vector<uint8_t>& removed,
                                         const Sphere& sphere, double density, double* budget_mm3);

}  // namespace ctsurg::sim
