// Embedding a surface in a tetrahedral mesh: each vertex follows the 4 nodes of the tet holding it
// with its barycentric weights (the FEM paper's coupling of a render surface to a tet mesh; used by
// explicit springs from tet edges and by the FEM models). A vertex outside every tet (a marching-cubes
// surface and a mesher's boundary differ by a fraction of a cell) takes the nearest tet by barycentric
// distance, with its weights clamped to >= 0 and renormalised; the coupling is on displacements
// (surface_coupling.h: v = v_rest + sum w u), so the rest surface is reproduced exactly either way.
//
// Point location: a uniform bucket grid over the tets' bounding boxes (cell about the mean edge
// length), searched in rings around the vertex's bucket. Units: LPS mm.
#pragma once

#include "ctsurg/core/tet_mesh_file.h"
#include "ctsurg/sim/surface/surface_coupling.h"

#include <vector>

namespace ctsurg::sim {

struct TetEmbeddingStats {
  int64_t inside = 0;          // vertices inside a tet (barycentric >= -1e-9)
  int64_t outside = 0;         // vertices placed in the nearest tet
  double max_outside_mm = 0;   // largest distance of an outside vertex to its tet (approximate: centroid
                               // distance scaled by the barycentric defect), mm
};

// vertices: #V x 3 LPS mm (the surface's rest vertices). Returns a coupling with slots 0..3 = the
// tet's nodes (slots 4..7 empty), rest_vertices = vertices. Throws InputError("tetmesh", ...) for an
// empty mesh, InputError("surface", "vertex N", ...) when a vertex is farther than max_distance_mm
// from every tet.
SurfaceCoupling embed_surface_in_tets(const std::vector<float>& vertices, const TetMesh& mesh, double max_distance_mm = 10.0,
                                      TetEmbeddingStats* stats = nullptr);

}  // namespace ctsurg::sim
