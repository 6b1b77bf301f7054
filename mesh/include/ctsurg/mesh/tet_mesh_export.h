// Export of a tetrahedral mesh to the formats FEM and visualisation programs open, chosen by suffix:
//   .vtu   VTK XML UnstructuredGrid, ASCII (ParaView, VTK, 3D Slicer): tets with cell data "labels" (the
//          name SegmentMesher uses) and FieldData SPACE = "LPS" (the frame marker Slicer reads)
//   .msh   Gmsh MSH 4.1 ASCII: one volume entity per label (physical group = label), tets only
//   .mesh  Medit (INRIA) ASCII, Dimension 3: vertices, Triangles (boundary faces, ref = inside label),
//          Tetrahedra (ref = label)
// Coordinates are LPS millimetres as in the .h5; tets keep their positive orientation (all three
// formats use the same vertex order convention for linear tets).
#pragma once

#include "ctsurg/core/tet_mesh_file.h"

#include <filesystem>
#include <string>

namespace ctsurg {

// "vtu", "msh", "mesh" for `path`'s suffix (case-insensitive), or "" when it is none of them.
std::string tet_mesh_export_format(const std::filesystem::path& path);

// Writes `mesh` to `path` in the format of `format_of`'s suffix (defaulting to `path`, so a temporary
// path is fine). InputError(path, "suffix", ...) for an unknown suffix; RuntimeError when writing
// fails. Not atomic by itself: callers write to an AtomicOutput's temp_path().
void export_tet_mesh(const std::filesystem::path& path, const TetMesh& mesh, const std::filesystem::path& format_of = {});

}  // namespace ctsurg
