// The tetrahedral mesh: a boundary-conforming volume mesh of one or several tissues (written by
// ctsurg-tetmesh, read by the FEM simulation stage), with its boundary surface and a quality report.
//
//   /provenance
//   /tetmesh/nodes          (#N, 3) float64  LPS mm
//   /tetmesh/tets           (#T, 4) int32    node indices, positively oriented:
//                                             (p1 - p0) . ((p2 - p0) x (p3 - p0)) > 0
//   /tetmesh/tet_labels     (#T)    uint16   tissue label of each tet (the mask's label)
//   /tetmesh/boundary_faces (#B, 3) int32    node indices of every face between two different
//                                             labels (or a label and the outside), counter-clockwise
//                                             seen from the side of face_labels[:, 1]
//   /tetmesh/face_labels    (#B, 2) uint16   (inside, outside) label of each boundary face: the
//                                             face's normal points from inside into outside; outside
//                                             is 0 on the organ's skin, the larger label on an interface
//   /tetmesh/quality/radius_edge_histogram (#bins) int64, with attribute radius_edge_bin_edges
//   /tetmesh attributes: nodes, tets, boundary_faces, frame "LPS", units "mm", labels (ids),
//                        mask_volume_mm3, seed, and the meshing criteria (criteria, JSON)
//   /tetmesh/quality attributes: see TetMeshQuality
//
// plus an XDMF sidecar (Tetrahedron topology, the tet labels as cell data). See docs/formats.md.
#pragma once

#include "ctsurg/core/provenance.h"

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace ctsurg {

// Shape quality of a tet mesh (see mesh/tet_mesh_quality.h for how each number is computed).
struct TetMeshQuality {
  double min_dihedral_deg = 0.0;       // smallest dihedral angle over all tets, degrees
  double max_dihedral_deg = 0.0;       // largest dihedral angle over all tets, degrees
  double min_radius_edge = 0.0;        // circumradius / shortest edge; sqrt(6)/4 = 0.612 for a regular tet
  double mean_radius_edge = 0.0;
  double max_radius_edge = 0.0;
  int64_t slivers = 0;                 // tets with a dihedral angle under sliver_threshold_deg
  double sliver_threshold_deg = 10.0;
  int64_t inverted = 0;                // tets with signed volume <= 0 (must be 0)
  double volume_mm3 = 0.0;             // sum of tet volumes
  std::vector<double> radius_edge_bin_edges;  // #bins + 1, increasing; the last bin is open above
  std::vector<int64_t> radius_edge_histogram; // #bins, tets per bin
};

struct TetMesh {
  std::vector<double> nodes;            // #N x 3, LPS mm, row-major
  std::vector<int32_t> tets;            // #T x 4, positively oriented
  std::vector<uint16_t> tet_labels;     // #T, tissue label
  std::vector<int32_t> boundary_faces;  // #B x 3, counter-clockwise seen from face_labels[:, 1]'s side
  std::vector<uint16_t> face_labels;    // #B x 2, (inside, outside)
  TetMeshQuality quality;
  double mask_volume_mm3 = 0.0;         // volume of the labelled voxels that were meshed
  uint64_t seed = 0;                    // random seed of the mesher
  std::string criteria;                 // JSON of the meshing criteria (mm, degrees)

  int64_t node_count() const { return static_cast<int64_t>(nodes.size() / 3); }
  int64_t tet_count() const { return static_cast<int64_t>(tets.size() / 4); }
  int64_t boundary_face_count() const { return static_cast<int64_t>(boundary_faces.size() / 3); }
};

// Throws InputError(file, "/tetmesh/...", ...) for an empty mesh, inconsistent array sizes or a node
// index out of range.
void validate_tet_mesh(const TetMesh& mesh, const std::string& file);
// Writes `path` (and its .xdmf sidecar) atomically; validates first.
void write_tet_mesh_file(const std::filesystem::path& path, const TetMesh& mesh, const Provenance& provenance);
// Reads a tet mesh file; InputError naming the file and object when it is not one, when an array has
// the wrong shape or when an index is out of range.
TetMesh read_tet_mesh_file(const std::filesystem::path& path);

}  // namespace ctsurg
