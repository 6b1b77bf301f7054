// Whether a static FEM problem's held components remove all six rigid motions (otherwise the stiffness
// matrix is singular and no solver may start). Used by fem_static_solver.cpp and
// fem_linear_static_solver.cpp before they assemble anything.
#pragma once

#include "ctsurg/sim/fem/fem_model.h"

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace ctsurg::sim {

// held: #N x 3 flags (1 = the component is fixed or prescribed); diag: the rest mesh's bounding-box
// diagonal (mm, to scale positions). The Gram matrix of the rigid modes (3 translations, 3 rotations
// about the mesh centre) restricted to the held rows of nodes that some tet uses must be well
// conditioned (smallest eigenvalue > 1e-10 x largest); otherwise throws InputError(where, "boundary
// conditions", ...) naming each free rigid motion (a translation along an axis, a rotation about an
// axis through a point in mm) and what to fix.
// The rigid motions that `held` leaves free, in words (rigid_mode_text; empty: none); held_rows: the
// number of held components of used nodes.
std::vector<std::string> free_rigid_modes(const FemModel& model, const std::vector<uint8_t>& held, double diag, int64_t* held_rows = nullptr);
void check_rigid_modes(const FemModel& model, const std::vector<uint8_t>& held, double diag, const char* where);

// A rigid velocity field v(x) = t + w x (x - centre) / diag in words: "translation along x", "rotation
// about the axis along z through (1.0, 2.0, 3.0) mm".
std::string rigid_mode_text(const Eigen::Vector3d& t, const Eigen::Vector3d& w, const Eigen::Vector3d& centre, double diag);

// The diagonal of the rest nodes' bounding box, mm.
double fem_bounding_diagonal(const FemModel& model);

}  // namespace ctsurg::sim
