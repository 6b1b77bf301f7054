// Shape quality of tetrahedra: dihedral angles, radius-edge ratio, signed volume, and the mesh's
// quality report (TetMeshQuality in core/tet_mesh_file.h). Pure functions over plain arrays.
//
// The measures are the ones Delaunay refinement bounds and that FEM conditioning depends on
// (Shewchuk, "What is a good linear finite element?", 2002): the radius-edge ratio R / l_min (Mesh_3's
// cell_radius_edge_ratio criterion; sqrt(6)/4 = 0.612 for the regular tet) cannot see slivers (four
// nearly coplanar points with a good ratio), the dihedral angles can: a sliver has one near 0 deg and
// one near 180 deg.
#pragma once

#include "ctsurg/core/tet_mesh_file.h"

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

namespace ctsurg {

// Signed volume of tet (p0, p1, p2, p3), mm^3: (p1 - p0) . ((p2 - p0) x (p3 - p0)) / 6; positive
// for a positively oriented tet.
double tet_signed_volume(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& p2,
                         const Eigen::Vector3d& p3);

// The six interior dihedral angles of a tet, degrees, at edges (01, 02, 03, 12, 13, 23). The angle
// at edge (a, b) is pi minus the angle between the outward normals of the two faces holding it. A
// degenerate tet (a face of zero area) gives 0 for the angles at that face.
std::array<double, 6> tet_dihedral_angles_deg(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                                              const Eigen::Vector3d& p2, const Eigen::Vector3d& p3);

// Circumradius / shortest edge (dimensionless). Infinite for a flat tet (no circumsphere).
double tet_radius_edge_ratio(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& p2,
                             const Eigen::Vector3d& p3);

// The quality report of a mesh.
//   nodes  #N x 3, mm (any frame)
//   tets   #T x 4 node indices
//   sliver_threshold_deg: a tet with any dihedral angle below it counts as a sliver
// The radius-edge histogram has bins [0.6, 0.7), [0.7, 0.8), ... [1.9, 2.0), [2.0, inf).
TetMeshQuality tet_mesh_quality(const std::vector<double>& nodes, const std::vector<int32_t>& tets,
                                double sliver_threshold_deg = 10.0);

}  // namespace ctsurg
