// Uniform ("red") refinement of a tet mesh: every tet split into eight at its edges' midpoints, so the
// refined mesh covers exactly the same domain with the same boundary and the same label interfaces
// (nested meshes). A discretisation's convergence can then be measured with the geometry held fixed:
// the answers at h, h/2 and h/4 differ only by the discretisation, and Richardson's estimate applies
// (docs/accuracy.md "The live mesh's own error").
//
// Each tet (x0, x1, x2, x3) gives its four corner tets (a corner and its three edges' midpoints) and
// four tets around the inner octahedron's shortest diagonal (Bey 1995, "Tetrahedral grid refinement":
// of the three diagonals x01-x23, x02-x13, x03-x12 the shortest; ties to the first). Children keep
// the parent's label and are positively oriented. Nodes: the parent's #N first, in order, then one
// midpoint per edge, edges numbered in the order (min node, max node) sorted; deterministic. Boundary
// faces are recomputed (each parent face gives four), the quality report is recomputed; mask volume,
// seed and criteria are kept, with `"refinements"` added to (or incremented in) the criteria's JSON.
//
// Sizes: nodes #N + #E, tets 8 #T. Memory: about 250 bytes per child tet at peak.
#pragma once

#include "ctsurg/core/tet_mesh_file.h"

namespace ctsurg {

// The mesh refined `times` times (0: a copy). InputError("tet mesh refinement", ...) when the mesh is
// not valid (validate_tet_mesh), times < 0, or the result would exceed 2^31 - 1 nodes or tets.
TetMesh refine_tet_mesh_uniformly(const TetMesh& mesh, int times = 1);

}  // namespace ctsurg
