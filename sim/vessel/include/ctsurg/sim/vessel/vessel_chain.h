// The medial-atom chain of a vessel: Huang et al. 2006 (section 5.1) model a vessel by its centerline
// as a mass-spring system of medial atoms {position, radius} and redraw the surface from the atoms
// (vessel_skinning.h). Here the springs are those of a discrete Cosserat rod (Kugelstadt & Schoemer
// 2016, "Position and orientation based Cosserat rods", SCA), so that a chain resists bending and
// twisting as a tube does, not only stretching:
//
//   atoms     a centerline point each (LPS minus the run's origin, mm), its radius and a lumped mass
//   segments  between consecutive atoms of a branch: rest length l, an orientation (a unit quaternion,
//             its d3 axis along the segment at rest, d1 rotation-minimising along the branch) and a
//             stretch-shear spring: strain c = R^T (x_b - x_a) / l - e3, energy l/2 c^T diag(kGA, kGA, EA) c
//   joints    between two segments sharing an atom: a bend-twist spring on the Darboux vector
//             Omega = 2/lbar Im((q_e r0)^* q_f) (r0 the rest relative rotation q_e^* q_f, so Omega is 0 at
//             rest whatever the rest angle), energy lbar/2 Omega^T diag(EI, EI, GJ) Omega, lbar the
//             joint's share of the rod (half of each segment)
//
// Junctions: the branches that meet at a centerline node share its atom; every pair of segments at a
// node of degree d is joined, each joint with 1/(d - 1) of the stiffness (a node of degree 2 is an
// ordinary atom; at a bifurcation the three pairs share the stiffness of two).
//
// Stiffnesses and masses from the wall (vessel_calibration.h): a segment's at the mean radius of its
// atoms, a joint's at its atom's radius; an atom's mass is half of each adjacent segment's.
//
// Units: mm, g; stiffnesses uN and uN mm^2 (vessel_calibration.h).
#pragma once

#include "ctsurg/core/centerline_file.h"
#include "ctsurg/sim/base/rigid_pose.h"
#include "ctsurg/sim/base/simulation_engine.h"
#include "ctsurg/sim/vessel/vessel_calibration.h"

#include <cstdint>
#include <string>
#include <vector>

namespace ctsurg::sim {

struct VesselJoint {
  int32_t e = 0, f = 0;                   // the two segments
  int32_t atom = 0;                       // the atom they share
  Quaternion rest_relative = kIdentityRotation;  // q_e^* q_f at rest
  double bending = 0, torsion = 0;        // EI, GJ, uN mm^2 (times the junction's share)
};

struct VesselChain {
  std::vector<double> rest;             // #A x 3 mm, local frame
  std::vector<double> radius;           // #A mm (the wall's mid-surface)
  std::vector<double> mass;             // #A g
  std::vector<int32_t> segment_atoms;   // #S x 2, (a, b) in the branch's direction
  std::vector<int32_t> segment_branch;  // #S
  std::vector<double> segment_length;   // #S rest length, mm
  std::vector<Quaternion> segment_rest_frame;  // #S
  std::vector<double> stretch, shear;   // #S EA, kappa G A (uN)
  std::vector<double> rotational_inertia;  // #S g mm^2
  std::vector<VesselJoint> joints;
  std::vector<int64_t> branch_offsets;  // #B + 1 into branch_atoms
  std::vector<int32_t> branch_atoms;    // the atoms of each branch in order (its nodes' atoms first and last)
  std::vector<int32_t> branch_first_segment;  // #B: branch b's k-th segment is branch_first_segment[b] + k
  VesselWall wall;

  int32_t atom_count() const { return static_cast<int32_t>(radius.size()); }
  int32_t segment_count() const { return static_cast<int32_t>(segment_length.size()); }
  int32_t branch_count() const { return static_cast<int32_t>(branch_first_segment.size()); }
};

// The chain of `centerline` (LPS mm) in the local frame LPS minus `origin`, with the wall's constants.
// InputError(where, "centerline", ...) for two consecutive points closer than 1e-6 mm (no direction)
// and as validate_vessel_wall for the wall; the centerline itself is assumed valid
// (validate_centerline, core/centerline_file.h).
VesselChain build_vessel_chain(const Centerline& centerline, const Vec3& origin, const VesselWall& wall, const std::string& where);

}  // namespace ctsurg::sim
