#include "ctsurg/sim/vessel/vessel_dynamics.h"

#include "ctsurg/core/error.h"
#include "vessel_math.h"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <algorithm>
#include <cmath>
#include <map>

namespace ctsurg::sim {

// The Gauss-Newton system: a fixed sparsity pattern of 3 x 3 blocks (nodes = atoms, then segments),
// stored in full (the factorisation reads the lower half), each block's entries found once.
struct VesselDynamics::Solver {
  Eigen::SparseMatrix<double> h;
  Eigen::VectorXd g, delta;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
  std::vector<std::array<int64_t, 3>> block;         // per block pair: the index of (3I, 3J + c) in the values
  std::vector<std::array<int32_t, 9>> segment_pairs;  // per segment: pairs of (a, b, s) x (a, b, s)
  std::vector<std::array<int32_t, 4>> joint_pairs;    // per joint: (e, f) x (e, f)
  std::vector<int32_t> diagonal;                      // per node
  std::vector<std::vector<int32_t>> node_pairs;       // per node: the pairs in its row or column
  std::vector<int32_t> pair_row, pair_col;
  double energy = 0;

  void add(int32_t pair, const M3& m) {
    double* values = h.valuePtr();
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) values[block[static_cast<size_t>(pair)][static_cast<size_t>(c)] + r] += m(r, c);
  }
  void set(int32_t pair, const M3& m) {
    double* values = h.valuePtr();
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) values[block[static_cast<size_t>(pair)][static_cast<size_t>(c)] + r] = m(r, c);
  }
};

namespace {

void put_entry(std::vector<double>& a, size_t i, const V3& v) { a[3 * i] = v.x(), a[3 * i + 1] = v.y(), a[3 * i + 2] = v.z(); }

}  // namespace

VesselDynamics::VesselDynamics(const VesselChain& chain, const VesselDynamicsOptions& options)
    : chain_(chain), options_(options), solver_(std::make_unique<Solver>()) {
  if (!(options.dt > 0) || !(options.mass_damping >= 0) || options.max_newton_iterations < 1 || !(options.tolerance_mm > 0)) {
    throw InputError("vessel", "dynamics", "needs dt > 0, mass_damping >= 0, max_newton_iterations >= 1, tolerance_mm > 0");
  }
  const size_t na = static_cast<size_t>(chain.atom_count()), ns = static_cast<size_t>(chain.segment_count());
  x = chain.rest;
  v.assign(3 * na, 0.0);
  q = chain.segment_rest_frame;
  w.assign(3 * ns, 0.0);
  force.assign(3 * na, 0.0);
  torque.assign(3 * ns, 0.0);
  fixed_atom_.assign(na, 0);
  fixed_segment_.assign(ns, 0);
  alive_.assign(ns, 1);
  prescribed_atom_.assign(na, 0);
  prescribed_segment_.assign(ns, 0);
  prescribed_x_.assign(3 * na, 0.0);
  prescribed_q_.assign(ns, kIdentityRotation);

  // The pattern: every block pair a segment or a joint couples, and every diagonal block.
  Solver& s = *solver_;
  const int32_t nodes = static_cast<int32_t>(na + ns);
  std::map<std::pair<int32_t, int32_t>, int32_t> ids;
  const auto pair = [&](int32_t i, int32_t j) {
    const auto [it, inserted] = ids.emplace(std::make_pair(j, i), static_cast<int32_t>(ids.size()));
    return it->second;
  };
  for (int32_t n = 0; n < nodes; ++n) s.diagonal.push_back(pair(n, n));
  for (size_t k = 0; k < ns; ++k) {
    const int32_t nd[3] = {chain.segment_atoms[2 * k], chain.segment_atoms[2 * k + 1], static_cast<int32_t>(na + k)};
    std::array<int32_t, 9> p{};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) p[static_cast<size_t>(3 * i + j)] = pair(nd[i], nd[j]);
    s.segment_pairs.push_back(p);
  }
  for (const VesselJoint& jn : chain.joints) {
    const int32_t nd[2] = {static_cast<int32_t>(na) + jn.e, static_cast<int32_t>(na) + jn.f};
    s.joint_pairs.push_back({pair(nd[0], nd[0]), pair(nd[0], nd[1]), pair(nd[1], nd[0]), pair(nd[1], nd[1])});
  }
  // ids is ordered by (column, row): the triplets go in column-major order, so each block's column
  // holds its 3 rows contiguously.
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(9 * ids.size());
  for (const auto& [key, id] : ids) {
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) triplets.emplace_back(3 * key.second + r, 3 * key.first + c, 0.0);
  }
  const Eigen::Index n = 3 * static_cast<Eigen::Index>(nodes);
  s.h.resize(n, n);
  s.h.setFromTriplets(triplets.begin(), triplets.end());
  s.h.makeCompressed();
  s.block.assign(ids.size(), {0, 0, 0});
  s.pair_row.assign(ids.size(), 0);
  s.pair_col.assign(ids.size(), 0);
  s.node_pairs.assign(static_cast<size_t>(nodes), {});
  for (const auto& [key, id] : ids) {
    const auto [col, row] = key;
    for (int c = 0; c < 3; ++c) {
      const Eigen::Index column = 3 * col + c;
      const int* begin = s.h.innerIndexPtr() + s.h.outerIndexPtr()[column];
      const int* end = s.h.innerIndexPtr() + s.h.outerIndexPtr()[column + 1];
      const int* found = std::lower_bound(begin, end, 3 * row);
      s.block[static_cast<size_t>(id)][static_cast<size_t>(c)] = found - s.h.innerIndexPtr();
    }
    s.pair_row[static_cast<size_t>(id)] = row;
    s.pair_col[static_cast<size_t>(id)] = col;
    s.node_pairs[static_cast<size_t>(row)].push_back(id);
    if (row != col) s.node_pairs[static_cast<size_t>(col)].push_back(id);
  }
  s.g.resize(n);
  s.ldlt.analyzePattern(s.h);
}

VesselDynamics::~VesselDynamics() = default;

void VesselDynamics::fix_atoms(const std::vector<int32_t>& atoms) {
  for (const int32_t a : atoms) {
    if (a < 0 || a >= chain_.atom_count()) throw InputError("vessel", "fixed", "atom " + std::to_string(a) + " out of range");
    fixed_atom_[static_cast<size_t>(a)] = 1;
  }
  for (size_t s = 0; s < fixed_segment_.size(); ++s) {
    fixed_segment_[s] = fixed_atom_[static_cast<size_t>(chain_.segment_atoms[2 * s])] && fixed_atom_[static_cast<size_t>(chain_.segment_atoms[2 * s + 1])];
  }
}

void VesselDynamics::prescribe_atom(int32_t a, const Vec3& p) {
  prescribed_atom_[static_cast<size_t>(a)] = 1;
  for (size_t c = 0; c < 3; ++c) prescribed_x_[3 * static_cast<size_t>(a) + c] = p[c];
}

void VesselDynamics::prescribe_segment(int32_t s, const Quaternion& frame) {
  prescribed_segment_[static_cast<size_t>(s)] = 1;
  prescribed_q_[static_cast<size_t>(s)] = frame;
}

void VesselDynamics::clear_prescribed() {
  std::fill(prescribed_atom_.begin(), prescribed_atom_.end(), 0);
  std::fill(prescribed_segment_.begin(), prescribed_segment_.end(), 0);
}

void VesselDynamics::cut_segment(int32_t s) {
  alive_[static_cast<size_t>(s)] = 0;
  put_entry(w, static_cast<size_t>(s), V3::Zero());
}

bool VesselDynamics::held_segment(size_t s) const { return fixed_segment_[s] || prescribed_segment_[s] || !alive_[s]; }

// Gradient (solver.g), energy, and with_matrix the Gauss-Newton matrix of E(y) - loads . y, plus the
// inertia term |y - y_pred|^2_M / (2 dt^2) when `inertia`; held unknowns get identity rows.
double VesselDynamics::assemble(bool inertia, const std::vector<double>& x_pred, const std::vector<Quaternion>& q_pred, bool with_matrix) {
  Solver& s = *solver_;
  const VesselChain& ch = chain_;
  const size_t na = static_cast<size_t>(ch.atom_count()), ns = static_cast<size_t>(ch.segment_count());
  s.g.setZero();
  if (with_matrix) std::fill(s.h.valuePtr(), s.h.valuePtr() + s.h.nonZeros(), 0.0);
  double energy = 0;
  const auto grad = [&](size_t node, const V3& value) { s.g.segment<3>(3 * static_cast<Eigen::Index>(node)) += value; };
  // Stretch and shear: c = R^T (x_b - x_a) / l - e3.
  for (size_t k = 0; k < ns; ++k) {
    if (!alive_[k]) continue;
    const size_t a = static_cast<size_t>(ch.segment_atoms[2 * k]), b = static_cast<size_t>(ch.segment_atoms[2 * k + 1]);
    const double l = ch.segment_length[k];
    const M3 rt = to_eigen(q[k]).toRotationMatrix().transpose();
    const V3 d = (at(x, b) - at(x, a)) / l;
    const V3 c = rt * d - V3::UnitZ();
    const V3 wd(l * ch.shear[k], l * ch.shear[k], l * ch.stretch[k]);
    const V3 wc = wd.cwiseProduct(c);
    energy += 0.5 * c.dot(wc);
    const M3 j[3] = {-rt / l, rt / l, rt * skew(d)};
    const size_t nd[3] = {a, b, na + k};
    for (int i = 0; i < 3; ++i) grad(nd[i], j[i].transpose() * wc);
    if (with_matrix) {
      M3 wj[3];
      for (int i = 0; i < 3; ++i) wj[i] = wd.asDiagonal() * j[i];
      for (int i = 0; i < 3; ++i)
        for (int m = 0; m < 3; ++m) s.add(s.segment_pairs[k][static_cast<size_t>(3 * i + m)], j[i].transpose() * wj[m]);
    }
  }
  // Bend and twist: Omega = 2 / lbar Im((q_e r0)^* q_f).
  for (size_t k = 0; k < ch.joints.size(); ++k) {
    const VesselJoint& jn = ch.joints[k];
    const size_t e = static_cast<size_t>(jn.e), f = static_cast<size_t>(jn.f);
    if (!alive_[e] || !alive_[f]) continue;
    double lbar = (held_segment(e) ? 0.0 : 0.5 * ch.segment_length[e]) + (held_segment(f) ? 0.0 : 0.5 * ch.segment_length[f]);
    if (lbar <= 0) lbar = 0.5 * (ch.segment_length[e] + ch.segment_length[f]);
    const Q p = to_eigen(q[e]) * to_eigen(jn.rest_relative);
    Q r = p.conjugate() * to_eigen(q[f]);
    if (r.w() < 0) r.coeffs() = -r.coeffs();
    const M3 d = 0.5 * (r.w() * M3::Identity() - skew(r.vec())) * p.toRotationMatrix().transpose();
    const V3 omega = 2 / lbar * r.vec();
    const V3 wd(lbar * jn.bending, lbar * jn.bending, lbar * jn.torsion);
    const V3 wo = wd.cwiseProduct(omega);
    energy += 0.5 * omega.dot(wo);
    const M3 jf = 2 / lbar * d;
    grad(na + e, -jf.transpose() * wo);
    grad(na + f, jf.transpose() * wo);
    if (with_matrix) {
      const M3 m = jf.transpose() * wd.asDiagonal() * jf;
      s.add(s.joint_pairs[k][0], m);
      s.add(s.joint_pairs[k][1], -m);
      s.add(s.joint_pairs[k][2], -m);
      s.add(s.joint_pairs[k][3], m);
    }
  }
  // Loads: gravity and forces on atoms, torques on segments.
  for (size_t a = 0; a < na; ++a) {
    const V3 f = at(force, a) + ch.mass[a] * V3(options_.gravity[0], options_.gravity[1], options_.gravity[2]);
    grad(a, -f);
    energy -= f.dot(at(x, a) - at(ch.rest, a));
  }
  for (size_t k = 0; k < ns; ++k) {
    const V3 t = at(torque, k);
    if (t.squaredNorm() == 0) continue;
    grad(na + k, -t);
    energy -= t.dot(rotation_log(to_eigen(q[k]) * to_eigen(ch.segment_rest_frame[k]).conjugate()));
  }
  // Inertia, and a tiny regularisation of the segments' rotations (a piece of one segment has a free
  // twist in a static solve).
  const double dt2 = options_.dt * options_.dt;
  for (size_t a = 0; a < na; ++a) {
    if (!inertia) break;
    const double m = ch.mass[a] / dt2;
    const V3 dx = at(x, a) - at(x_pred, a);
    grad(a, m * dx);
    energy += 0.5 * m * dx.squaredNorm();
    if (with_matrix) s.add(s.diagonal[a], m * M3::Identity());
  }
  for (size_t k = 0; k < ns; ++k) {
    const double m = inertia ? ch.rotational_inertia[k] / dt2 : 0.0;
    if (inertia) {
      const V3 dr = rotation_log(to_eigen(q[k]) * to_eigen(q_pred[k]).conjugate());
      grad(na + k, m * dr);
      energy += 0.5 * m * dr.squaredNorm();
    }
    if (with_matrix) s.add(s.diagonal[na + k], (m + 1e-9 * ch.shear[k] * ch.segment_length[k]) * M3::Identity());
  }
  // Held unknowns: identity rows and columns, no gradient.
  const auto hold = [&](size_t node) {
    s.g.segment<3>(3 * static_cast<Eigen::Index>(node)).setZero();
    if (!with_matrix) return;
    for (const int32_t p : s.node_pairs[node]) s.set(p, M3::Zero());
    s.set(s.diagonal[node], M3::Identity());
  };
  for (size_t a = 0; a < na; ++a)
    if (fixed_atom_[a] || prescribed_atom_[a]) hold(a);
  for (size_t k = 0; k < ns; ++k)
    if (held_segment(k)) hold(na + k);
  s.energy = energy;
  return energy;
}

int VesselDynamics::newton(bool inertia, const std::vector<double>& x_pred, const std::vector<Quaternion>& q_pred, int max_iterations) {
  Solver& s = *solver_;
  const size_t na = static_cast<size_t>(chain_.atom_count()), ns = static_cast<size_t>(chain_.segment_count());
  int it = 0;
  while (it < max_iterations) {
    assemble(inertia, x_pred, q_pred, true);
    s.ldlt.factorize(s.h);
    if (s.ldlt.info() != Eigen::Success) throw RuntimeError("vessel: the Gauss-Newton matrix could not be factorised");
    s.delta = s.ldlt.solve(-s.g);
    ++it;
    double largest = 0;
    for (size_t a = 0; a < na; ++a) {
      const V3 d = s.delta.segment<3>(3 * static_cast<Eigen::Index>(a));
      put_entry(x, a, at(x, a) + d);
      largest = std::max(largest, d.norm());
    }
    for (size_t k = 0; k < ns; ++k) {
      const V3 d = s.delta.segment<3>(3 * static_cast<Eigen::Index>(na + k));
      if (d.squaredNorm() == 0) continue;
      q[k] = to_quaternion((rotation_exp(d) * to_eigen(q[k])).normalized());
      largest = std::max(largest, d.norm());
    }
    if (!(largest == largest)) break;  // NaN: the caller's guard reports it
    if (largest < options_.tolerance_mm) break;
  }
  return it;
}

int VesselDynamics::step() {
  const size_t na = static_cast<size_t>(chain_.atom_count()), ns = static_cast<size_t>(chain_.segment_count());
  const double dt = options_.dt;
  const std::vector<double> x_old = x;
  const std::vector<Quaternion> q_old = q;
  std::vector<double> x_pred(3 * na);
  std::vector<Quaternion> q_pred(ns);
  for (size_t a = 0; a < na; ++a) {
    put_entry(x_pred, a, at(x, a) + dt * at(v, a));
    if (fixed_atom_[a]) put_entry(x_pred, a, at(x, a));
    if (prescribed_atom_[a]) put_entry(x_pred, a, at(prescribed_x_, a));
  }
  for (size_t k = 0; k < ns; ++k) {
    q_pred[k] = to_quaternion((rotation_exp(dt * at(w, k)) * to_eigen(q[k])).normalized());
    if (fixed_segment_[k] || !alive_[k]) q_pred[k] = q[k];
    if (prescribed_segment_[k]) q_pred[k] = prescribed_q_[k];
  }
  x = x_pred;
  q = q_pred;
  const int it = newton(true, x_pred, q_pred, options_.max_newton_iterations);
  const double keep = 1 / (1 + options_.mass_damping * dt);
  for (size_t a = 0; a < na; ++a) put_entry(v, a, keep / dt * (at(x, a) - at(x_old, a)));
  for (size_t k = 0; k < ns; ++k) {
    put_entry(w, k, alive_[k] ? V3(keep / dt * rotation_log(to_eigen(q[k]) * to_eigen(q_old[k]).conjugate())) : V3::Zero());
  }
  return it;
}

int VesselDynamics::solve_static(int max_iterations) {
  const size_t na = static_cast<size_t>(chain_.atom_count()), ns = static_cast<size_t>(chain_.segment_count());
  for (size_t a = 0; a < na; ++a)
    if (prescribed_atom_[a]) put_entry(x, a, at(prescribed_x_, a));
  for (size_t k = 0; k < ns; ++k)
    if (prescribed_segment_[k]) q[k] = prescribed_q_[k];
  const int it = newton(false, x, q, max_iterations);
  std::fill(v.begin(), v.end(), 0.0);
  std::fill(w.begin(), w.end(), 0.0);
  return it;
}

double VesselDynamics::elastic_energy() const {
  // The springs only: the assembly without loads, inertia or matrix, on a copy of the loads set to 0.
  const VesselChain& ch = chain_;
  double energy = 0;
  for (size_t k = 0; k < ch.segment_length.size(); ++k) {
    if (!alive_[k]) continue;
    const size_t a = static_cast<size_t>(ch.segment_atoms[2 * k]), b = static_cast<size_t>(ch.segment_atoms[2 * k + 1]);
    const double l = ch.segment_length[k];
    const V3 c = to_eigen(q[k]).toRotationMatrix().transpose() * (at(x, b) - at(x, a)) / l - V3::UnitZ();
    energy += 0.5 * l * (ch.shear[k] * (c.x() * c.x() + c.y() * c.y()) + ch.stretch[k] * c.z() * c.z());
  }
  for (const VesselJoint& jn : ch.joints) {
    const size_t e = static_cast<size_t>(jn.e), f = static_cast<size_t>(jn.f);
    if (!alive_[e] || !alive_[f]) continue;
    double lbar = (held_segment(e) ? 0.0 : 0.5 * ch.segment_length[e]) + (held_segment(f) ? 0.0 : 0.5 * ch.segment_length[f]);
    if (lbar <= 0) lbar = 0.5 * (ch.segment_length[e] + ch.segment_length[f]);
    Q r = (to_eigen(q[e]) * to_eigen(jn.rest_relative)).conjugate() * to_eigen(q[f]);
    if (r.w() < 0) r.coeffs() = -r.coeffs();
    const V3 o = 2 / lbar * r.vec();
    energy += 0.5 * lbar * (jn.bending * (o.x() * o.x() + o.y() * o.y()) + jn.torsion * o.z() * o.z());
  }
  return energy;
}

double VesselDynamics::kinetic_energy() const {
  double e = 0;
  for (size_t a = 0; a < chain_.mass.size(); ++a) e += 0.5 * chain_.mass[a] * at(v, a).squaredNorm();
  for (size_t k = 0; k < chain_.rotational_inertia.size(); ++k) e += 0.5 * chain_.rotational_inertia[k] * at(w, k).squaredNorm();
  return e;
}

}  // namespace ctsurg::sim
