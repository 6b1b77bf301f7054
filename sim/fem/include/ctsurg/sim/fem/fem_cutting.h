// Cutting a tetrahedral mesh: a blade separates the elements it passes between, and the nodes they
// shared are duplicated so each side moves on its own (the fracture of Parker & O'Brien 2009, "Real-time
// deformation and fracture in a game environment", section 4: separation along element faces by node
// splitting). Elements are never removed, split or created:
//
//   - the volume and the mass stay exactly as they were (each element keeps its rest shape and nodes'
//     share; a duplicated node takes its rest position and its displacement from the node it copies);
//   - no sliver or inverted element can appear (SOFA's users report twisted elements and crashes after
//     tet removal: those come from the remeshing this does not do);
//   - the critical time step does not change (it is set by the elements, which are the same);
//   - the incision follows the elements' faces: it is as jagged as the mesh (a 6 mm mesh cuts in 6 mm
//     facets). That is the price; the rendered surface, embedded in the tets, opens along the blade's
//     triangles (surface/surface_cutting.h's remove_crossed_triangles).
//
// Which faces: an interior face of the original mesh is separated when the segment between its two
// elements' centroids (current positions) crosses a blade triangle (the same segment-triangle test as
// the spring cuts, base/kernels/segment_triangle_impl.h). Separations accumulate over cuts.
//
// Which nodes: for each node of a newly separated face, the elements around it are grouped by the
// faces through the node that are still joined (union-find); groups only ever split, so each keeps the
// id its elements use unless a sibling with a lower element already has it, in which case it gets a
// new node, appended: deterministic, whatever the thread count. A crack that ends inside the mesh
// (its front) leaves the elements around a front node joined around the front: that node is not split
// until a later cut reaches past it.
//
// Linear (4-node) tets only. Units: mm.
#pragma once

#include "ctsurg/sim/base/tool_shapes.h"
#include "ctsurg/sim/fem/fem_model.h"

#include <cstdint>
#include <functional>
#include <vector>

namespace ctsurg::sim {

struct FemCutResult {
  int64_t faces_separated = 0;         // by this cut
  std::vector<int32_t> new_node_parent;  // one per node appended: the node it was copied from
};

class FemTetSeparation {
 public:
  // The mesh's interior faces (tets #T x 4). InputError("fem cut", "elements", ...) for a quadratic model.
  explicit FemTetSeparation(const FemModel& model);
  // The same from bare linear tets (#T x 4 ids below node_count).
  FemTetSeparation(const std::vector<int32_t>& tets, int32_t node_count);

  // Separates the elements across `blade` (positions: the current nodes #N x 3 mm, N = node_count) and
  // splits their nodes: `tets` (#T x 4, the current ids) is updated in place; the new nodes are
  // node_count, node_count + 1, ... in the result's order.
  FemCutResult cut(std::vector<int32_t>& tets, int32_t node_count, const std::vector<double>& positions, const Triangle& blade);

  // Separates the interior faces between elements a and b (original ids, a < b) for which
  // separate(a, b) holds, and splits their nodes as cut() does: bodies made before a run (the labels
  // of a multi-organ mesh, a plane between two regions: fem/fem_contact.h).
  FemCutResult separate_where(std::vector<int32_t>& tets, int32_t node_count, const std::function<bool(int32_t a, int32_t b)>& separate);

  int64_t faces_separated() const;   // in all cuts so far
  int64_t interior_faces() const { return static_cast<int64_t>(faces_.size()); }

 private:
  struct Face {
    int32_t a, b;         // its two elements, a < b
    int32_t nodes[3];     // original node ids
  };
  void split(std::vector<int32_t>& tets, int32_t node_count, std::vector<int32_t>& touched, FemCutResult& r);

  std::vector<Face> faces_;
  std::vector<uint8_t> separated_;
  std::vector<int32_t> original_;        // per current node: the original node it descends from
  std::vector<int32_t> tet_offsets_, tet_list_;    // original node -> its elements (CSR)
  std::vector<int32_t> face_offsets_, face_list_;  // original node -> the interior faces through it (CSR)
};

// The mesh's connected pieces (elements joined by shared nodes): a piece id per node (#N; -1 for a node no
// element uses) and the number of pieces.
int32_t fem_mesh_pieces(const std::vector<int32_t>& tets, int32_t node_count, std::vector<int32_t>& piece_of_node);

// The boundary of linear tets (#T x 4): the faces used by one element only, #F x 3 node ids wound
// counter-clockwise seen from outside, in element order (and each element's faces in a fixed order).
// Two bodies pressed together, or the lips of a cut, have separate nodes, so each keeps its own faces.
std::vector<uint32_t> fem_boundary_faces(const std::vector<int32_t>& tets);

}  // namespace ctsurg::sim
