// Cutting: removing every spring whose segment crosses a blade. A blade swept along a path is a set
// of triangles (the blade's edge at two consecutive times and the area between); each call removes
// the springs crossing one triangle. Grid model: the spring's bit is cleared on both particles (the
// papers' single-spring cutting granularity, Mosegaard & Sorensen 2005, section 2.7.3); explicit
// model: the spring's alive flag is cleared.
//
// The test is on the particles' current positions (LPS mm); a segment touching the triangle (its
// boundary included) is cut; a degenerate triangle (zero area) cuts nothing. Both particles of a
// grid spring evaluate it on the same ordered segment (lower id first), so they always agree.
// Kernels: src/spring_cutting_impl.h (per particle for the grid, per spring for the explicit model).
#pragma once

#include "ctsurg/sim/base/particle_state.h"
#include "ctsurg/sim/base/tool_shapes.h"
#include "ctsurg/sim/springs/explicit_spring_model.h"
#include "ctsurg/sim/springs/spring_grid_model.h"

#include <array>
#include <cstdint>

namespace ctsurg::sim {

// Returns the number of springs cut (each counted once). state has the model's particle count, else
// InputError("cut", "state", ...).
int64_t cut_springs_crossing_triangle(SpringGridModel& model, const ParticleState& state, const Triangle& blade, int threads = 0);
int64_t cut_springs_crossing_triangle(ExplicitSpringModel& model, const ParticleState& state, const Triangle& blade,
                                      int threads = 0);

}  // namespace ctsurg::sim
