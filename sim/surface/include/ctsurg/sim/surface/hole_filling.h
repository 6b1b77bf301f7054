// Closing the holes a cut leaves in a triangle surface, with new triangles over the existing vertices
// (a trajectory fixes its vertex count for a whole run: only the triangles change from frame to frame).
//
// The holes are the loops of boundary edges that were interior edges before the cut: edges used by one
// triangle now and by two in the uncut surface. Edges on the surface's own boundary (an open surface)
// are never filled, and a loop that reaches them is left open. A loop that visits a vertex twice (a
// pinched lip) is split there into simple loops.
//
// Each loop is triangulated by the minimal-area dynamic programme of Barequet & Sharir, "Filling gaps in
// the boundary of a polyhedron" (CAGD 1995), the first stage of Liepa, "Filling holes in meshes"
// (SGP 2003, section 3: weight = triangle area; Liepa's dihedral-angle term and his refinement, which
// adds vertices, are left out): W(i, j) = min over i < k < j of W(i, k) + W(k, j) + area(v_i, v_k, v_j),
// O(n^3) time, O(n^2) memory. Loops longer than kMaxDynamicLoop vertices are closed by a fan from their
// first vertex instead (linear; still closed, possibly folded). The new triangles run each boundary edge
// opposite to the triangle beside it, so the filled surface is oriented like the surface around it.
//
// Seams. A textured surface repeats a vertex along its texture seams (one copy per chart), so its seams
// look like boundary edges. weld_coincident() maps each vertex to the lowest id at exactly the same
// rest position; edges are counted between welded ids, so the two charts' triangles at a seam share
// their edge. Loops are found and closed in welded ids (copies at one rest position are tied to the
// particles alike and move together). A marching-cubes surface also holds slivers between two distinct
// vertices at one position; welded, they have no area and are skipped. Where welding makes an edge with
// four faces (two sheets touching) a cut removing one of them leaves that edge with three, which is not
// seen as a hole's edge: such a hole stays open.
//
// Shapes and units: vertices #V x 3 (mm, any frame), triangles #F x 3 vertex ids.
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace ctsurg::sim {

// Loops above this length are fanned (the dynamic programme would cost n^3 / 6 area evaluations).
inline constexpr std::size_t kMaxDynamicLoop = 600;

// #V ids: for each vertex the lowest id with exactly the same position in `vertices` (#V x 3).
std::vector<uint32_t> weld_coincident(const std::vector<float>& vertices);

// The undirected edges used by exactly one triangle of `triangles` (#F x 3), less seams, in welded ids
// (weld: weld_coincident(), or empty for none), each as (min id, max id), sorted: an uncut surface's own
// boundary, which fill_cut_holes leaves open.
std::vector<std::pair<uint32_t, uint32_t>> boundary_edges(const std::vector<uint32_t>& triangles,
                                                          const std::vector<uint32_t>& weld = {});

// The boundary loops of `triangles` (#F x 3) made of edges not in `own_boundary` (boundary_edges() of the
// uncut surface with the same weld), each a list of (welded) vertex ids in the order the filling
// triangles run them (opposite to the triangle beside each edge). Deterministic: loops start at their
// smallest unvisited edge.
std::vector<std::vector<uint32_t>> cut_hole_loops(const std::vector<uint32_t>& triangles,
                                                  const std::vector<std::pair<uint32_t, uint32_t>>& own_boundary,
                                                  const std::vector<uint32_t>& weld = {});

// Triangles (#T x 3, T = n - 2) closing one loop of n >= 3 vertex ids (cut_hole_loops' order), minimal
// total area over `vertices` (#V x 3 mm), or a fan when n > kMaxDynamicLoop. Empty for n < 3.
std::vector<uint32_t> triangulate_loop(const std::vector<uint32_t>& loop, const std::vector<float>& vertices);

// Every cut hole of `triangles` closed: the new triangles only (#T x 3), to be appended to `triangles`.
std::vector<uint32_t> fill_cut_holes(const std::vector<uint32_t>& triangles, const std::vector<float>& vertices,
                                     const std::vector<std::pair<uint32_t, uint32_t>>& own_boundary,
                                     const std::vector<uint32_t>& weld = {});

}  // namespace ctsurg::sim
