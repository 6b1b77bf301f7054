// Contact between the bodies of a tet mesh, and of a body with itself: organs pressed together never
// pass through each other, and the lips of a cut or a fold do not pass through their own tissue.
//
// Bodies. A scenario's mesh may hold several organs (a label each) or one organ split into regions
// (planes): separate_bodies() separates the faces between them before the run (fem_cutting.h: nodes
// split, elements kept), so each is its own body of one FEM model, meeting the others at the surfaces
// where they touched. The bodies are the mesh's connected pieces, recomputed after every cut.
//
// Detection, every `interval_steps` steps (the pairs found enforced every step; default every step), by
// spatial hashing of the boundary (sim/collision: Teschner et al. 2003; the table rebuilt each call, linear
// in the boundary's size): every boundary node within `distance` of a boundary face it is not a corner of
// and behind it ((x - q) . n < 0, n the face's outward normal, q the closest point) is penetrating; the
// nearest such face is its way out. A face of another body is always contact; a face of the node's own
// body only when the surfaces face each other (the node's outward normal, the area-weighted mean of its
// faces', has n_v . n < 0): proximity to one's own surface where it curves is not contact (self-contact:
// folds, the lips of a cut). Detected every step, a penetration stays far shallower than the distance
// (a tenth of an element by default), so the nearest face is the one crossed and the projection small.
//
// Response: position-based projection (Müller et al. 2007, "Position based dynamics", section 3.4 and
// eq. 5-9 with the collision constraint of 4.4 generalised to a node and a face): for the constraint
// C = (x - sum_i b_i x_i) . n >= 0 (b: the closest point's barycentric coordinates), lambda = -C / (w +
// sum_i b_i^2 w_i) and x += w lambda n, x_i -= w_i b_i lambda n (w: inverse masses; fixed nodes 0), so
// momentum is conserved and the heavier side moves less. Gauss-Seidel over the pairs in their sorted
// order, `iterations` sweeps: deterministic, independent of the thread count. Applied to the
// displacements after each explicit step, as the sphere probe's projection; the position change also
// changes the velocity (central differences), an inelastic contact.
//
// Units: mm, g.
#pragma once

#include "ctsurg/sim/base/fixed_regions.h"
#include "ctsurg/sim/base/real.h"
#include "ctsurg/sim/fem/fem_model.h"

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

namespace ctsurg {
struct TetMesh;
}

namespace ctsurg::sim {

struct FemContactOptions {
  bool enabled = false;
  bool self = true;          // also within one body (folds, the lips of a cut)
  double distance_mm = 0;    // detection distance; 0: a tenth of the mean boundary edge
  int iterations = 4;        // projection sweeps per step (>= 1)
  int interval_steps = 1;    // detection every this many steps; the pairs found are enforced every step
  int threads = 0;           // the hash's OpenMP threads; 0: automatic
};

class FemContact {
 public:
  // The boundary faces, their bodies and the boundary nodes of `model` (linear tets). Throws
  // InputError("fem contact", field, ...) for options out of range or a quadratic model.
  FemContact(const FemModel& model, const FemContactOptions& options);

  // Detects and resolves contacts for displacements u (#N x 3 mm, Real, in place) with inverse masses
  // inv_mass (#N, 0 = fixed or held). Returns the contacts resolved.
  int64_t resolve(const FemModel& model, Real* u, const Real* inv_mass);

  // The deepest penetration now (mm, >= 0): the largest -(x - q) . n over the facing pairs (tests).
  double deepest_penetration(const FemModel& model, const Real* u) const;

  int32_t bodies() const { return bodies_; }
  int64_t boundary_faces() const { return static_cast<int64_t>(faces_.size() / 3); }
  double distance_mm() const { return distance_; }

 private:
  struct Pair {
    uint32_t node, face;
    double b[3];
  };
  void detect(const std::vector<double>& x, std::vector<Pair>& pairs) const;
  // The pair's constraint at positions x: the face's unit normal n and C = (x_node - q) . n (q: the point
  // of barycentric coordinates p.b); false for a degenerate face.
  bool constraint(const std::vector<double>& x, const Pair& p, std::array<double, 3>& n, double& C) const;

  FemContactOptions options_;
  double distance_ = 0;                // mm: the detection distance
  std::vector<uint32_t> boundary_nodes_;  // #B node ids (the faces' corners), increasing
  std::vector<uint32_t> boundary_body_;   // #B
  std::vector<uint32_t> compact_faces_;   // #F x 3 indices into boundary_nodes_
  int32_t bodies_ = 0;
  std::vector<uint32_t> faces_;        // #F x 3, outward (counter-clockwise seen from outside)
  std::vector<uint32_t> face_body_;    // #F
  std::vector<uint32_t> node_body_;    // #N (boundary nodes; others unused)
  std::vector<uint8_t> on_boundary_;   // #N
  std::vector<std::pair<std::pair<uint32_t, uint32_t>, uint32_t>> edge_faces_;  // (edge (lo, hi), face), sorted
  std::vector<Pair> pairs_;            // found at the last detection
  int since_detection_ = 0;
  std::vector<double> scratch_;        // positions
  std::vector<uint8_t> moved_;         // per node: moved by the last resolve
};

// Separates the bodies of a tet mesh before a run: each tet's region is its label (by_label) and the
// sides of the planes its centroid is on (each HalfSpace: point, normal; the mesh's frame), and every
// node that tets of several regions share is copied, one per region, so each region moves on its own.
// Updates mesh.nodes, mesh.tets (and tet_labels, when tets are removed); the mesh's boundary_faces and
// face_labels are cleared (they no longer describe it). gap_mm > 0 first takes out the tets whose centroid lies within gap_mm / 2
// of a plane, so the regions start apart (nodes no tet uses stay, unused: the solvers hold them).
// Pieces of a region smaller than 1 % of the mesh (at least 20 tets) join their neighbour's region, so a
// plane's jagged seam leaves no free fragments.
struct BodySeparation {
  int64_t faces = 0;         // faces between tets of different bodies (now apart)
  int64_t nodes_split = 0;   // nodes copied so that no node is shared between bodies
  int64_t tets_removed = 0;  // by the gap
};
BodySeparation separate_bodies(TetMesh& mesh, bool by_label, const std::vector<HalfSpace>& planes, double gap_mm = 0);

}  // namespace ctsurg::sim
