// The surface of a trajectory simulated without a surface file (an FEM scenario with no model.surface:
// ctsurg-sim records the tet mesh's boundary faces over its nodes), so ctsurg-render draws it without
// --surface: the trajectory's rest vertices and its first topology, with area-weighted vertex normals
// (no normal map, no texture atlas). Later topologies (cuts) come from the trajectory frame by frame,
// as for any surface.
//
// Units: LPS mm.
#pragma once

#include "ctsurg/core/surface_mesh_file.h"
#include "ctsurg/core/trajectory_file.h"

#include <string>

namespace ctsurg {

// Throws InputError(trajectory_name, field, ...) when the trajectory names a surface file (render it with
// that file) or records no triangles (nothing to draw: a point set).
SurfaceMesh trajectory_surface(const Trajectory& trajectory, const std::string& trajectory_name);

}  // namespace ctsurg
