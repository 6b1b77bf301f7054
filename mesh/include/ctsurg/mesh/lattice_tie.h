// Tying surface vertices to the lattice a simulation moves: for each vertex, the lattice cell that
// holds it, the trilinear weights of the cell's 8 corner nodes, and the nearest inside node (the
// nearest-particle mapping of the spring-mass papers, Mosegaard & Sorensen 2005, section 2.6).
//
// marching_cubes() writes the tie as it extracts the surface; this recomputes it after the vertices
// have moved (smoothing, decimation), so that the stored weights still reproduce every vertex.
#pragma once

#include "ctsurg/core/surface_mesh_file.h"
#include "ctsurg/core/volume.h"

namespace ctsurg {

// Recomputes mesh.grid_cell, mesh.grid_weights and mesh.nearest_node from mesh.vertices.
//
// mesh   vertices #V x 3 LPS mm; mesh.lattice must be field's lattice and mesh.iso its isovalue
// field  the scalar field the surface was extracted from (node inside: value >= mesh.iso)
// grid_cell     the cell (i, j, k) whose box holds the vertex, clamped to the lattice's cells (a
//               vertex outside the lattice gets weights outside [0, 1] that still reproduce it)
// grid_weights  trilinear weights of that cell's corners (corner c at (c & 1, c >> 1 & 1, c >> 2 & 1)),
//               summing to 1
// nearest_node  the inside node nearest to the vertex in LPS mm, searched in the 4 x 4 x 4 nodes
//               around the cell and then in growing shells; the cell's lower corner when the field has
//               no inside node at all
// Throws InputError("mesh", "lattice", ...) when the lattices differ. Parallel (OpenMP), deterministic.
void tie_surface_to_lattice(SurfaceMesh& mesh, const Volume<float>& field);

}  // namespace ctsurg
