// The vessel's surface redrawn from its medial atoms each frame (Huang et al. 2006, section 5.1: the
// centerline deforms, the surface is reconstructed from it): a ring of `spokes` vertices around every
// atom of every branch, at the atom's radius in the plane perpendicular to the axis C_{i-1}C_{i+1}
// (one-sided at a piece's ends), consecutive rings joined by quads (two triangles each), the ends of
// every piece capped by a fan over the end ring (no extra vertex: the vertex count never changes,
// which a trajectory needs, core/trajectory_file.h). Two ways to place a ring's first spoke:
//
//   spokes  the paper's construction, eq. 15-16: the first spoke perpendicular to C_{i-1}C_{i+1} and in
//           the plane xOy (vessel_frames.h, plane_spoke), the others rotated about that axis by 2 pi j /
//           spokes. Each ring is chosen on its own, so where the axis passes near z the rings turn
//           against each other by up to 180 degrees (a visible twist of the mesh; measured in
//           tests/sim/vessel/test_vessel_skinning.cpp and docs/vessel.md).
//   rmf     rotation-minimising frames (double reflection, Wang et al. 2008; vessel_frames.h) carried
//           with the chain's torsion: with the chain's segment frames (vessel_chain.h; at rest they
//           are the rotation-minimising frames of the branch, and the rod carries them with its
//           bending and twist) a ring's first spoke is the mean of its adjacent segments' d1 made
//           perpendicular to the ring's axis, so a twisted vessel's mesh turns with it; without frames
//           (a bare centerline) the double reflection runs along each piece from eq. 15's first spoke.
//
// Junctions: each branch has its own ring at the shared junction atom, perpendicular to its own
// axis, and is capped there: the branches' tubes overlap around the junction (a closed tube each,
// not one welded surface; the overlap hides the caps). Cuts: a cut segment removes its quads and caps
// both rings it joined (vessel_engine.h).
//
// Vertices: ring g (the g-th entry of chain.branch_atoms, branch by branch) holds vertices g spokes ...
// g spokes + spokes - 1, counter-clockwise about the branch direction; triangles face outwards.
// Units: mm, the chain's frame.
#pragma once

#include "ctsurg/sim/base/rigid_pose.h"
#include "ctsurg/sim/vessel/vessel_chain.h"

#include <cstdint>
#include <vector>

namespace ctsurg::sim {

enum class VesselSkinning { rmf, spokes };

class VesselSkin {
 public:
  // spokes in [3, 1024]. The chain must outlive this object.
  VesselSkin(const VesselChain& chain, int spokes, VesselSkinning mode);

  int spokes() const { return spokes_; }
  VesselSkinning mode() const { return mode_; }
  int64_t vertex_count() const { return static_cast<int64_t>(chain_.branch_atoms.size()) * spokes_; }
  // The triangles for the segments alive (#S, 1 = alive): quads between rings of alive segments, caps
  // at every piece's ends (a ring alone between two cuts gets none).
  void update_topology(const std::vector<uint8_t>& segment_alive);
  const std::vector<uint32_t>& triangles() const { return triangles_; }  // #F x 3
  int64_t cap_triangles() const { return caps_; }                       // of them, in caps (the last ones)

  // The vertices (#V x 3 mm) for atom positions (#A x 3 mm) and, for rmf, the segments' frames (#S;
  // nullptr: rotation-minimising frames of the bare centerline). `first_spokes` (optional, #rings x 3)
  // receives each ring's first spoke direction.
  void vertices(const std::vector<double>& positions, const std::vector<Quaternion>* frames, std::vector<float>& out,
                std::vector<double>* first_spokes = nullptr) const;

 private:
  const VesselChain& chain_;
  int spokes_;
  VesselSkinning mode_;
  std::vector<uint8_t> alive_;
  std::vector<uint32_t> triangles_;
  int64_t caps_ = 0;
};

// The largest turn (degrees) between the first spokes of neighbouring rings (#rings x 3, as
// VesselSkin::vertices gives them) of each piece, after parallel transport of one ring's spoke onto the
// next ring's plane (the minimal rotation between their axes): 0 for rotation-minimising frames, up to
// 180 for eq. 15's spokes where the axis passes z. `positions`: the atoms (#A x 3 mm).
double max_spoke_turn_deg(const VesselChain& chain, const std::vector<double>& positions, const std::vector<double>& first_spokes);

}  // namespace ctsurg::sim
