#include "ctsurg/sim/vessel/vessel_chain.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/vessel/vessel_frames.h"
#include "vessel_math.h"

#include <cmath>

namespace ctsurg::sim {

VesselChain build_vessel_chain(const Centerline& cl, const Vec3& origin, const VesselWall& wall, const std::string& where) {
  validate_vessel_wall(wall, where);
  VesselChain ch;
  ch.wall = wall;
  const int64_t nodes = cl.node_count();
  // One atom per node, then each branch's interior points.
  std::vector<double> node_radius(static_cast<size_t>(nodes), 0.0);
  std::vector<int> node_uses(static_cast<size_t>(nodes), 0);
  for (int64_t n = 0; n < nodes; ++n) {
    for (size_t c = 0; c < 3; ++c) ch.rest.push_back(cl.nodes[3 * static_cast<size_t>(n) + c] - origin[c]);
  }
  ch.radius.assign(static_cast<size_t>(nodes), 0.0);
  ch.branch_offsets.push_back(0);
  for (int64_t b = 0; b < cl.branch_count(); ++b) {
    const int64_t p0 = cl.branch_offsets[static_cast<size_t>(b)], p1 = cl.branch_offsets[static_cast<size_t>(b) + 1];
    for (int64_t p = p0; p < p1; ++p) {
      int32_t atom;
      if (p == p0 || p == p1 - 1) {
        atom = cl.branch_nodes[2 * static_cast<size_t>(b) + (p == p0 ? 0 : 1)];
        node_radius[static_cast<size_t>(atom)] += cl.radius[static_cast<size_t>(p)];
        ++node_uses[static_cast<size_t>(atom)];
      } else {
        atom = static_cast<int32_t>(ch.radius.size());
        for (size_t c = 0; c < 3; ++c) ch.rest.push_back(cl.points[3 * static_cast<size_t>(p) + c] - origin[c]);
        ch.radius.push_back(cl.radius[static_cast<size_t>(p)]);
      }
      ch.branch_atoms.push_back(atom);
    }
    ch.branch_offsets.push_back(static_cast<int64_t>(ch.branch_atoms.size()));
  }
  for (int64_t n = 0; n < nodes; ++n) {
    const size_t i = static_cast<size_t>(n);
    if (node_uses[i] == 0) throw InputError(where, "centerline", "node " + std::to_string(n) + " is the end of no branch");
    ch.radius[i] = node_radius[i] / node_uses[i];
  }
  const size_t atoms = ch.radius.size();
  ch.mass.assign(atoms, 0.0);
  const auto pos = [&](int32_t a) { return V3(ch.rest[3 * static_cast<size_t>(a)], ch.rest[3 * static_cast<size_t>(a) + 1], ch.rest[3 * static_cast<size_t>(a) + 2]); };

  // Segments, with rotation-minimising rest frames along each branch.
  std::vector<std::vector<int32_t>> at_atom(atoms);  // the segments at each atom
  for (int32_t b = 0; b < static_cast<int32_t>(ch.branch_offsets.size()) - 1; ++b) {
    const int64_t k0 = ch.branch_offsets[static_cast<size_t>(b)], k1 = ch.branch_offsets[static_cast<size_t>(b) + 1];
    ch.branch_first_segment.push_back(ch.segment_count());
    // The segments' directions as a polyline of their midpoints' tangents: the frame of segment k is
    // d3 = its direction, d1 the rotation-minimising normal carried along the segment directions.
    const size_t ns = static_cast<size_t>(k1 - k0 - 1);
    std::vector<double> mid(3 * ns), dir(3 * ns), normal(3 * ns);
    for (size_t k = 0; k < ns; ++k) {
      const int32_t a = ch.branch_atoms[static_cast<size_t>(k0) + k], bb = ch.branch_atoms[static_cast<size_t>(k0) + k + 1];
      const V3 d = pos(bb) - pos(a);
      const double l = d.norm();
      if (!(l > 1e-6)) {
        throw InputError(where, "centerline", "branch " + std::to_string(b) + " has two consecutive points " + std::to_string(l) +
                                                  " mm apart (atoms need distinct positions)");
      }
      const V3 m = 0.5 * (pos(a) + pos(bb)), u = d / l;
      for (int c = 0; c < 3; ++c) mid[3 * k + static_cast<size_t>(c)] = m[c], dir[3 * k + static_cast<size_t>(c)] = u[c];
    }
    const V3 t0(dir[0], dir[1], dir[2]);
    const Vec3 s0 = plane_spoke({t0[0], t0[1], t0[2]});
    rotation_minimizing_normals(mid.data(), dir.data(), ns, s0, normal.data());
    for (size_t k = 0; k < ns; ++k) {
      const int32_t a = ch.branch_atoms[static_cast<size_t>(k0) + k], bb = ch.branch_atoms[static_cast<size_t>(k0) + k + 1];
      const V3 d3(dir[3 * k], dir[3 * k + 1], dir[3 * k + 2]), d1(normal[3 * k], normal[3 * k + 1], normal[3 * k + 2]);
      M3 r;
      r.col(0) = d1;
      r.col(1) = d3.cross(d1);
      r.col(2) = d3;
      const int32_t s = ch.segment_count();
      ch.segment_atoms.push_back(a);
      ch.segment_atoms.push_back(bb);
      ch.segment_branch.push_back(b);
      const double l = (pos(bb) - pos(a)).norm();
      ch.segment_length.push_back(l);
      ch.segment_rest_frame.push_back(to_quaternion(Q(r).normalized()));
      const ChainStiffness ks = tube_stiffness(wall, 0.5 * (ch.radius[static_cast<size_t>(a)] + ch.radius[static_cast<size_t>(bb)]));
      ch.stretch.push_back(ks.stretch);
      ch.shear.push_back(ks.shear);
      ch.rotational_inertia.push_back(ks.rotational_inertia_per_mm * l);
      ch.mass[static_cast<size_t>(a)] += 0.5 * l * ks.mass_per_mm;
      ch.mass[static_cast<size_t>(bb)] += 0.5 * l * ks.mass_per_mm;
      at_atom[static_cast<size_t>(a)].push_back(s);
      at_atom[static_cast<size_t>(bb)].push_back(s);
    }
  }
  // Joints: each pair of segments at an atom, the stiffness shared at junctions.
  for (size_t a = 0; a < atoms; ++a) {
    const auto& segs = at_atom[a];
    const size_t d = segs.size();
    if (d < 2) continue;
    const double share = 1.0 / static_cast<double>(d - 1);
    const ChainStiffness k = tube_stiffness(wall, ch.radius[a]);
    for (size_t i = 0; i < d; ++i) {
      for (size_t j = i + 1; j < d; ++j) {
        VesselJoint jn;
        jn.e = segs[i];
        jn.f = segs[j];
        jn.atom = static_cast<int32_t>(a);
        const Q qe = to_eigen(ch.segment_rest_frame[static_cast<size_t>(jn.e)]), qf = to_eigen(ch.segment_rest_frame[static_cast<size_t>(jn.f)]);
        jn.rest_relative = to_quaternion((qe.conjugate() * qf).normalized());
        jn.bending = share * k.bending;
        jn.torsion = share * k.torsion;
        ch.joints.push_back(jn);
      }
    }
  }
  return ch;
}

}  // namespace ctsurg::sim
