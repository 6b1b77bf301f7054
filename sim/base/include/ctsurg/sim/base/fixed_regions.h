// Fixed boundary regions: selections of particles (or FEM nodes) by their rest position (a box, the side
// of a plane) or by tissue label (a tet mesh's tet labels here; a grid model's cells by the occupancy
// grid's /grid/label: particles_with_label in springs/spring_grid_model.h), which a scenario fixes (inverse mass 0: they
// never move, gravity included; verlet_step_impl.h).
//
// Units: LPS mm (particle_state.h).
#pragma once

#include "ctsurg/sim/base/particle_state.h"

#include <array>
#include <cstdint>
#include <vector>

namespace ctsurg {
struct TetMesh;  // core/tet_mesh_file.h
}

namespace ctsurg::sim {

struct Box {
  std::array<double, 3> min{0, 0, 0};  // LPS mm, lower corner (inclusive)
  std::array<double, 3> max{0, 0, 0};  // LPS mm, upper corner (inclusive), >= min
};

struct HalfSpace {
  std::array<double, 3> point{0, 0, 0};   // LPS mm, a point of the plane
  std::array<double, 3> normal{0, 0, 1};  // direction into the selected side (any length > 0)
};

// Ids (increasing) of the particles whose rest position (#P x 3 LPS mm) is in the box. Throws
// InputError("fixed region", "box", ...) when min > max or a bound is not finite.
std::vector<int32_t> particles_in_box(const std::vector<Real>& rest_positions, const Box& box);
// Ids (increasing) of the particles with (rest - point) . normal >= 0. Throws InputError("fixed region",
// "half_space", ...) for a zero or non-finite normal.
std::vector<int32_t> particles_in_half_space(const std::vector<Real>& rest_positions, const HalfSpace& half_space);
// The nodes (increasing) of the tets of `mesh` with label `label`.
std::vector<int32_t> nodes_with_label(const TetMesh& mesh, uint16_t label);

// Fixes the particles `ids` (inverse mass 0). Throws InputError("fixed region", "particle", ...) for an
// id out of range.
void fix_particles(ParticleState& state, const std::vector<int32_t>& ids);

}  // namespace ctsurg::sim
