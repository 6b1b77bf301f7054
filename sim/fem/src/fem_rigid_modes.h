// Whether a static FEM problem's held components remove all six rigid motions (otherwise the stiffness
// matrix is singular and no solver may start). Used by fem_static_solver.cpp and
// fem_linear_static_solver.cpp before they assemble anything.
#pragma once

#include "ctsurg/sim/fem/fem_model.h"

#include <cstdint>
#include <vector>

namespace ctsurg::sim {

// held: #N x 3 flags (1 = the component is fixed or prescribed); diag: the rest mesh's bounding-box
// diagonal (mm, to scale positions). The Gram matrix of the rigid modes (3 translations, 3 rotations
// about the mesh centre) restricted to the held rows of nodes that some tet uses must be well
// conditioned (smallest eigenvalue > 1e-10 x largest); otherwise throws InputError(where, "boundary
// conditions", ...) saying that a rigid motion is free and what to fix.
void check_rigid_modes(const FemModel& model, const std::vector<uint8_t>& held, double diag, const char* where);

// The diagonal of the rest nodes' bounding box, mm.
double fem_bounding_diagonal(const FemModel& model);

}  // namespace ctsurg::sim
