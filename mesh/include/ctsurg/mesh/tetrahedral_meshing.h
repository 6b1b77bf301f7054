// Boundary-conforming Delaunay tetrahedral meshing of a labelled image (CGAL Mesh_3), with sliver
// perturbation and exudation: the "improved Delaunay meshing with sliver removal" of the FEM paper
// (seeds/003, section 2). Refinement follows Rineau & Yvinec, "A generic software design for Delaunay
// refinement meshing" (2007); perturbation Tournois, Srinivasan & Alliez (2009); exudation Cheng et
// al., "Sliver exudation" (2000); ODT smoothing Alliez et al. (2005).
//
// The image's index axes are meshed as an axis-aligned lattice with its spacing (CGAL's Image_3); the
// nodes are then mapped to LPS through the full index-to-world transform of the lattice, so tilted,
// sheared or mirrored lattices come out where they were scanned. A mirrored lattice (det < 0) flips
// orientation, which is undone so every tet is positively oriented.
//
// Deterministic: a fixed seed for every random choice, sequential meshing, optimisers without time
// limits; the same input and parameters give the same mesh, node for node.
#pragma once

#include "ctsurg/core/tet_mesh_file.h"
#include "ctsurg/core/volume.h"

#include <cstdint>
#include <string>
#include <vector>

namespace ctsurg {

enum class TetOptimiser { none, odt, lloyd };

// Meshing criteria (Mesh_3's, in mm and degrees) and options.
struct TetMeshingOptions {
  double cell_size_mm = 2.4;        // upper bound on tet circumradius
  double facet_size_mm = 2.4;       // upper bound on boundary-facet circumradius (surface Delaunay balls)
  double facet_distance_mm = 0.5;   // upper bound on the distance of a facet's circumcentre to the surface
  double radius_edge_ratio = 2.0;   // upper bound on circumradius / shortest edge (>= 2 guarantees termination)
  double facet_angle_deg = 25.0;    // lower bound on boundary-facet angles (<= 30 guarantees termination)
  // Global smoothing before perturbation. None by default: on the heart it changes neither the
  // minimum dihedral angle (12 deg either way) nor the slivers (0), costs 3-6x the meshing time, and
  // ODT can leave slivers at interfaces between labels (see docs/mesh.md).
  TetOptimiser optimiser = TetOptimiser::none;
  int optimiser_iterations = 20;    // iterations of ODT / Lloyd (a fixed count keeps it deterministic)
  double sliver_bound_deg = 12.0;   // perturbation and exudation try to lift every dihedral angle above this
  uint64_t seed = 0;                // random seed (domain construction and perturbation)
  std::vector<uint16_t> labels;     // labels to mesh; empty = every non-zero label
};

// Checks the options; InputError("--<option>", "", problem) for a non-finite, zero or negative
// criterion or an out-of-range bound.
void validate_tet_meshing_options(const TetMeshingOptions& options);

// Volume of the voxels with a wanted label (every non-zero one when `wanted_labels` is empty), mm^3.
double labelled_volume_mm3(const Volume<uint16_t>& labels, const std::vector<uint16_t>& wanted_labels);
// Area of the voxel faces between a wanted voxel and a voxel of another value, mm^2 (the staircase
// surface, up to 1.5x the smooth one).
double labelled_surface_area_mm2(const Volume<uint16_t>& labels, const std::vector<uint16_t>& wanted_labels);

// Expected number of tets for `options` (an overestimate by design, used to refuse absurd criteria
// before meshing): the interior volume over that of a regular tet with circumradius 0.7 x cell size,
// plus three tets behind each boundary facet of circumradius 0.7 x facet size (or smaller where the
// facet distance forces it) over the surface area.
//   meshed_volume_mm3: labelled_volume_mm3; surface_area_mm2: labelled_surface_area_mm2
int64_t estimate_tet_count(double meshed_volume_mm3, double surface_area_mm2, const TetMeshingOptions& options);

// Meshes the voxels of `labels` whose value is one of options.labels (all non-zero ones when empty);
// each label becomes one subdomain (tissue) and the surfaces between labels are meshed conformingly.
//   labels: the label lattice (voxel centres in LPS mm through labels.geometry)
// Returns the mesh with nodes in LPS mm, positively oriented tets, tet labels, boundary faces with
// their (inside, outside) labels, and quality computed; mask_volume_mm3 is the volume of the meshed
// voxels. InputError(source_name, "labels", ...) when no voxel has a requested label; RuntimeError when
// CGAL produces no cells.
TetMesh tetrahedral_mesh(const Volume<uint16_t>& labels, const TetMeshingOptions& options,
                         const std::string& source_name);

}  // namespace ctsurg
