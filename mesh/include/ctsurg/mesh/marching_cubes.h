// Marching cubes: the isosurface {x : f(x) = iso} of a scalar field sampled on a lattice, as a
// closed, consistently oriented triangle mesh with one shared vertex per crossed lattice edge.
//
// Lattice: the field's samples sit at the nodes (voxel centres) of `field.geometry`; a cell is the
// box between 8 neighbouring nodes. A node is inside when value >= iso.
//
// The case table (all 256 sign patterns of a cell's 8 corners) is built by the program, not copied
// from a published table (Lorensen & Cline 1987 had ambiguous faces that crack):
//  1. On each of the cell's 6 faces, walk the 4 corners counter-clockwise seen from outside the
//     cell. For every maximal run of consecutive inside corners, one segment joins the crossing
//     where the walk enters the run to the crossing where it leaves it. On an ambiguous face (two
//     diagonal inside corners) the runs are single corners, so the inside corners are always
//     separated ("separate positive", Nielson & Hamann 1991, used as a fixed rule rather than
//     decided by the asymptotic value).
//  2. Each crossed cell edge lies on 2 faces and is entered on one and left on the other, so the
//     segments chain into disjoint closed loops.
//  3. Each loop is triangulated by the minimum-weight triangulation (dynamic programming) of its
//     polygon at edge midpoints, weighting each triangle by perimeter^2 / area to avoid slivers, and
//     refusing, where it can, diagonals whose two ends lie on one face (they would lie in that face
//     and could be shared with the neighbour's triangles).
// Why no cracks and consistent orientation: the segments on a face depend only on that face's 4
// corner signs, so the two cells sharing a face make the same segments between the same (shared)
// vertices; seen from the two cells the face's orientation is opposite, so the segment, which is a
// boundary edge of exactly one triangle in each cell, is used once in each direction. Diagonals
// stay inside one cell. Hence every mesh edge away from the lattice border has exactly two
// triangles, with opposite orientations: a closed, oriented 2-manifold when the field is outside on
// the lattice border (pad it). Triangles are counter-clockwise seen from outside (from the inside
// region towards decreasing values).
//
// Parallel structure after VTK's flying edges (Schroeder, Maynard & Geveci 2015,
// vtkFlyingEdges3D.cxx): parallel over z-slices of nodes with OpenMP. Pass 1 counts, per slice, the
// crossed lattice edges whose lower node is in the slice and the triangles of the cells above it;
// an exclusive prefix sum gives every slice its first vertex and triangle; pass 2 writes vertices
// and triangles into arrays allocated once. No locks, no atomics, and the output (ordering
// included) is identical for any thread count.
#pragma once

#include "ctsurg/core/surface_mesh_file.h"
#include "ctsurg/core/volume.h"

namespace ctsurg {

struct MarchingCubesOptions {
  int threads = 0;  // OpenMP threads; 0 = OpenMP's default
};

// Extracts the isosurface of `field` at `iso`.
//
// field  scalar volume; its geometry (LPS mm, x fastest, direction matrix included) places the mesh
// iso    isovalue in the field's units; inside = value >= iso
// Returns a SurfaceMesh (surface_mesh_file.h):
//   vertices      #V x 3 LPS mm, one per lattice edge whose ends are on opposite sides, at the
//                 linear interpolation of the two values; ordered by slice k, then row j, then node
//                 i, then edge axis x, y, z
//   normals       #V x 3 unit, outward: minus the field's gradient (central differences at the
//                 nodes, one-sided on the border, mapped to LPS by the inverse transpose of the
//                 index-to-world matrix), interpolated along the edge; where that gradient vanishes,
//                 the edge direction from its inside node to its outside node
//   triangles     #F x 3 uint32, counter-clockwise seen from outside; ordered by cell (i fastest)
//   grid_cell     #V x 3 int32, the cell holding the vertex (its edge's lower node, clamped to the
//                 last cell on the lattice's upper faces)
//   grid_weights  #V x 8 float, trilinear weights of that cell's corners (corner c at offset
//                 (c & 1, c >> 1 & 1, c >> 2 & 1)); they sum to 1 and reproduce the vertex
//   nearest_node  #V x 3 int32, the inside end of the vertex's edge: the nearest inside node on an
//                 isotropic lattice (the nearest-particle mapping of the spring-mass papers)
//   lattice, iso  copied from the input; quantity and source_dataset are left for the caller
// The mesh is empty when no lattice edge crosses `iso`. Throws InputError("field", ...) for a
// non-finite iso or a lattice with fewer than 2 nodes on an axis, RuntimeError when the mesh
// would have more than 2^32 - 1 vertices.
SurfaceMesh marching_cubes(const Volume<float>& field, double iso, const MarchingCubesOptions& options = {});

// True when some node on the lattice's outer faces is inside (value >= iso): the surface is then
// open there (marching cubes has no cells beyond the lattice). Pad the field to close it.
bool inside_touches_border(const Volume<float>& field, double iso);

}  // namespace ctsurg
