// Degenerate triangles of a surface extracted on a lattice: what they are, how to find them, and how
// to remove them from a closed, consistently oriented 2-manifold without breaking it.
//
// Where they come from: marching cubes puts a vertex on every crossed lattice edge at the linear
// interpolation of the two node values. Where a node's value equals the isovalue exactly (occupancy
// fractions are multiples of 1/n, phantom HU values multiples of a step), every edge from that node
// to an outside neighbour gets a vertex at the node itself: several vertices at one position, and
// triangles with two coincident corners. Assimp's glTF exporter joins identical vertices, so those
// become triangles with a repeated index, which the Khronos glTF validator reports as
// ACCESSOR_INDEX_TRIANGLE_DEGENERATE (1594 of the 29 852 triangles of the demo heart's surface).
// Values just off the isovalue give near-zero-area slivers instead.
//
// Definition. With h the lattice's smallest spacing (mm), triangle (a, b, c) is degenerate when
//  1. two of its indices are equal (kRepeatedIndex), or
//  2. two of its corners have equal float32 positions (kCoincidentCorners: what an exporter that
//     joins identical vertices turns into 1), or
//  3. its area is below kMinAreaFraction * h^2 = 1e-6 h^2 (kTinyArea), or
//  4. its smallest interior angle is below kMinAngleDegrees = 1 degree (kSliver).
// Areas and angles are computed in double from the float32 positions. A triangle is counted once,
// under the first of these it meets.
//
// Removal (remove_degenerate_triangles), serial and in index order, so deterministic:
//  1. Merge: every edge shorter than kMergeDistanceFraction * h = 1e-4 h is collapsed.
//  2. Repair: every degenerate triangle, in triangle order, until a pass changes nothing (at most
//     32 passes). A cap (largest angle at least 150 degrees) has its longest edge flipped first;
//     any other (a needle, or a tiny triangle) has its shortest edge collapsed first; when that is
//     refused, the other operations are tried in turn (the collapse the other way, the flip, the
//     collapses of the other edges, the other flips). No edge longer than kMaxCollapseFraction * h
//     = 0.2 h is ever collapsed, so no triangle moves farther than that.
//  3. Only with may_move_vertices (a smoothed surface, whose vertices have left their lattice edges
//     anyway): a vertex of a triangle still degenerate (the cap's apex first) moves to the mean of
//     its one-ring projected on the ring's tangent plane when that folds no triangle and leaves its
//     fan fewer degenerate triangles (or the same number and a larger smallest angle); then step 2
//     again.
//  4. Components (through shared vertices) whose triangles are all degenerate (a lone node
//     exactly at the isovalue gives one of zero size), or that still hold a degenerate triangle and
//     have less area than one cell face h^2 or at most 4 vertices (a noise blob of a few nodes,
//     which smoothing shrinks to a speck; a tetrahedron has no valid collapse or flip), are
//     dropped whole; unreferenced vertices are removed.
// A collapse u -> v keeps v's position (an endpoint, so the vertex stays on its lattice edge and
// the surface gains no new geometry) and is refused unless
//  - the edge has one or two triangles and the link condition holds (the vertices adjacent to both
//    u and v are exactly the far corners of those triangles: no non-manifold edge or vertex, no
//    change of genus), and the far corners keep at least 3 neighbours;
//  - no surviving triangle around u turns over: its new normal keeps a positive dot product with
//    its old one, or, when the old one was too small to trust (area below 1e-6 h^2), with the area
//    vector of u's one-ring (and the collapse is refused when that is as small);
//  - u is not on a border of an open surface unless the edge is a border edge (borders stay put).
// Two obstacles are removed first when they are what refuses a short collapse:
//  - Thin handles. Where the surface touches itself at a node exactly at the isovalue (or nearly),
//    MC joins the two sheets by a handle of zero width: the edge's ends u, v and a third vertex w
//    are pairwise joined by edges but (u, v, w) is no face, so the link condition fails. Collapsing
//    would pinch the handle into a non-manifold vertex; instead the surface is cut along the
//    3-cycle and both sides closed by a triangle (u, v, w) (cut_handle), which the collapse then
//    removes with the edge. The surface stays a closed oriented 2-manifold (one handle fewer, or
//    one component more) and moves no more than the collapse moves it.
//  - Tents. A far corner with only 3 neighbours (a vertex standing over the triangle of its
//    neighbours) would be left with 2; it is removed first and its three triangles replaced by
//    that triangle, when it stands no farther than 0.2 h from it or the tetrahedron they make has
//    no volume (below 1e-6 h^3: a fin of two coincident triangles, which MC leaves at nodes exactly
//    at the isovalue).
// A flip of edge (a, b) between (a, b, c) and (b, a, d) to (c, a, d), (d, b, c) is refused when c
// and d are already joined, when a or b would keep fewer than 3 neighbours, when either new
// triangle turns over against the pair's area vector, or when it does not raise the pair's
// smallest angle. Orientation is kept throughout: every step rewrites indices inside
// counter-clockwise triangles.
//
// Measured (ctsurg-surface, before smoothing; docs/mesh.md): the demo heart grid (2.4 mm cells)
// has 1594 degenerate triangles of 29 852, all coincident corners, removed by 794 merges, 3
// handle cuts and 3 zero-size pieces dropped (no vertex moved, volume unchanged); the heart CT's 150 HU isosurface (1.5 mm, noisy
// contrast blood pool) has 7620 of 454 136, all removed (longest collapse 0.063 mm). Quantised and
// continuous random fields (tests/mesh/test_degenerate_triangles.cpp) end with none.
#pragma once

#include "ctsurg/core/surface_mesh_file.h"

#include <cstdint>
#include <string>
#include <vector>

namespace ctsurg {

inline constexpr double kMinAreaFraction = 1e-6;        // of h^2
inline constexpr double kMinAngleDegrees = 1.0;
inline constexpr double kMergeDistanceFraction = 1e-4;  // of h
inline constexpr double kMaxCollapseFraction = 0.2;     // of h: no longer edge is collapsed

enum class Degeneracy : uint8_t { kNone = 0, kRepeatedIndex, kCoincidentCorners, kTinyArea, kSliver };

// "none", "repeated index", "coincident corners", "tiny area", "sliver".
const char* degeneracy_name(Degeneracy d);

// Which of the definition's cases triangle t of `mesh` meets (kNone when none).
// mesh     #V x 3 float32 LPS mm vertices, #F x 3 triangles; t in [0, #F)
// cell_mm  h, the lattice's smallest spacing, > 0
Degeneracy triangle_degeneracy(const SurfaceMesh& mesh, int64_t t, double cell_mm);

struct DegenerateTriangleCount {
  int64_t repeated_index = 0, coincident_corners = 0, tiny_area = 0, sliver = 0;
  int64_t total() const { return repeated_index + coincident_corners + tiny_area + sliver; }
  std::string summary() const;  // "12 (3 repeated index, 9 coincident corners, 0 tiny area, 0 sliver)"
};

// Counts the degenerate triangles of `mesh` by case (the one check the tool and the tests use).
// cell_mm  h, > 0; InputError("mesh", "cell size", ...) otherwise. Parallel (OpenMP), deterministic.
DegenerateTriangleCount count_degenerate_triangles(const SurfaceMesh& mesh, double cell_mm);

// h for a surface tied to a lattice: the smallest of mesh.lattice's spacings (mm).
double lattice_cell_mm(const SurfaceMesh& mesh);

struct DegenerateRemovalStats {
  int64_t merged = 0;              // edges collapsed in the merge step (length < 1e-4 h)
  int64_t collapsed = 0;           // needle edges collapsed in the repair step
  int64_t flipped = 0;             // cap edges flipped
  int64_t handles_cut = 0;         // thin handles cut open so that a collapse could proceed
  int64_t tents_removed = 0;       // valence-3 vertices removed so that a collapse could proceed
  int64_t relaxed = 0;             // vertices moved (only with may_move_vertices)
  double longest_collapse_mm = 0.0;  // the longest collapsed edge: how far a vertex's triangles moved
  int64_t dropped_components = 0;  // components removed (all degenerate, or degenerate and tiny)
  DegenerateTriangleCount before, after;  // counts on entry and on return (after.total() is 0 unless
                                          // some collapse or flip was refused everywhere)
};

// Removes the degenerate triangles of `mesh` in place as described above. Triangles are rewritten
// and renumbered, and unused vertices dropped; every per-vertex array present (normals, the lattice
// tie, uvs, tangents, source_vertex) is carried along with its vertex, so a vertex keeps its
// position, normal and tie (they stay exact: no vertex moves unless may_move_vertices).
// mesh               #V x 3 LPS mm, #F x 3 counter-clockwise triangles; a closed oriented 2-manifold
//                    stays one (an open one keeps its borders)
// cell_mm            h, > 0; InputError("mesh", "cell size", ...) otherwise
// may_move_vertices  allow step 3 (the moved vertices' normals and tie are then stale: recompute
//                    them, recompute_vertex_normals() and tie_surface_to_lattice())
DegenerateRemovalStats remove_degenerate_triangles(SurfaceMesh& mesh, double cell_mm, bool may_move_vertices = false);

}  // namespace ctsurg
