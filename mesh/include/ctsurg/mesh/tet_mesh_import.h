// Import of a tetrahedral mesh made by another mesher (SegmentMesher, Gmsh, TetGen, MMG, fTetWild,
// meshio, ctsurg's own exports), chosen by suffix:
//   .vtu   VTK XML UnstructuredGrid, format="ascii" data arrays only (binary and appended data are
//          refused with a message saying so); VTK_TETRA cells (type 10); other cell types are
//          skipped and counted; labels from the cell data array "labels" (SegmentMesher, ctsurg),
//          "label", "gmsh:physical", "medit:ref" or "CellEntityIds", else every tet label 1
//   .msh   Gmsh MSH 2.2 or 4.1 ASCII; 4-node tets (type 4), label = physical tag (else the
//          elementary/entity tag); other elements skipped
//   .mesh  Medit ASCII (MeshVersionFormatted 1 or 2, Dimension 3); Tetrahedra with their reference
//          as label; Vertices/Triangles/Edges/... read past
// Coordinates are taken as LPS millimetres (the frame ctsurg writes; a file in another frame must
// be converted first).
//
// Checks (InputError naming the file, the element (1-based as in the file's order of tets) and the
// problem): node indices out of range, a tet with a repeated node or zero volume (|6V| <= 1e-12 l^3,
// l its longest edge), two tets on the same four nodes, labels outside 1..65535, non-finite
// coordinates, no tets. Negatively oriented tets are flipped (two nodes swapped) and counted. Nodes
// no tet uses are dropped and counted. Then the boundary faces (as the mesher's: between two labels
// or a label and the outside, counter-clockwise seen from the outside, inside = the smaller label)
// and the quality report (tet_mesh_quality.h) are computed.
#pragma once

#include "ctsurg/core/tet_mesh_file.h"

#include <cstdint>
#include <filesystem>
#include <string>

namespace ctsurg {

struct TetMeshImport {
  TetMesh mesh;                // positively oriented, with boundary faces and quality
  std::string format;          // "vtu", "msh 2.2", "msh 4.1", "mesh"
  int64_t flipped = 0;         // tets that were negatively oriented in the file
  int64_t unused_nodes = 0;    // nodes of the file no tet uses (dropped)
  int64_t skipped_cells = 0;   // cells/elements that are not 4-node tets (skipped)
  bool labels_from_file = true;  // false: the file had no label array and every tet is label 1
};

// "vtu", "msh", "mesh" for `path`'s suffix (case-insensitive), or "" when it is none of them.
std::string tet_mesh_import_format(const std::filesystem::path& path);

// Reads and checks a tet mesh file (see above).
TetMeshImport import_tet_mesh(const std::filesystem::path& path);

// Boundary faces of a positively oriented labelled tet mesh: every face of one tet (outside label 0)
// or of two tets with different labels. Writes mesh.boundary_faces (#B x 3, counter-clockwise seen
// from outside) and mesh.face_labels (#B x 2, inside, outside), in a deterministic order (by the
// tet and face that first holds them).
void compute_boundary_faces(TetMesh& mesh);

}  // namespace ctsurg
