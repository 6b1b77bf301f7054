#include "ctsurg/sim/fem/fem_contact.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/tet_mesh_file.h"
#include "ctsurg/sim/collision/vertex_triangle_contacts.h"
#include "ctsurg/sim/fem/fem_cutting.h"
#include "mesh_graph.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numeric>
#include <string>

namespace ctsurg::sim {
namespace {

constexpr const char* kContactWhere = "fem contact";

std::array<double, 3> face_normal(const std::vector<double>& x, const uint32_t* f) {  // not normalised: 2 x area
  const double* a = &x[3 * static_cast<size_t>(f[0])];
  const double* b = &x[3 * static_cast<size_t>(f[1])];
  const double* c = &x[3 * static_cast<size_t>(f[2])];
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  return {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
}

}  // namespace

FemContact::FemContact(const FemModel& model, const FemContactOptions& options) : options_(options) {
  if (model.order != 1) throw InputError(kContactWhere, "elements", "contact runs on linear (4-node) tets");
  if (options.iterations < 1 || options.iterations > 100) throw InputError(kContactWhere, "iterations", "must be 1 .. 100");
  if (options.interval_steps < 1 || options.interval_steps > 1000) throw InputError(kContactWhere, "interval_steps", "must be 1 .. 1000");
  if (!(std::isfinite(options.distance_mm) && options.distance_mm >= 0)) throw InputError(kContactWhere, "distance_mm", "must be finite and >= 0");
  const int32_t nn = model.node_count();
  std::vector<int32_t> body;
  bodies_ = fem_mesh_pieces(model.tets, nn, body);
  on_boundary_.assign(static_cast<size_t>(nn), 0);
  node_body_.assign(static_cast<size_t>(nn), 0);
  for (int32_t n = 0; n < nn; ++n) node_body_[static_cast<size_t>(n)] = static_cast<uint32_t>(std::max(body[static_cast<size_t>(n)], 0));
  faces_ = fem_boundary_faces(model.tets);
  double edge_sum = 0;
  int64_t edges = 0;
  for (size_t f = 0; f < faces_.size(); f += 3) {
    for (size_t k = 0; k < 3; ++k) {
      on_boundary_[faces_[f + k]] = 1;
      const double* p = &model.nodes[3 * static_cast<size_t>(faces_[f + k])];
      const double* q = &model.nodes[3 * static_cast<size_t>(faces_[f + (k + 1) % 3])];
      edge_sum += std::sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
      ++edges;
    }
    face_body_.push_back(node_body_[faces_[f]]);
  }
  // Detection within a tenth of an element: found every step, a penetration is far shallower.
  distance_ = options.distance_mm > 0 ? options.distance_mm : (edges ? 0.1 * edge_sum / static_cast<double>(edges) : 0.1);
  std::vector<int32_t> compact(static_cast<size_t>(nn), -1);
  for (int32_t n = 0; n < nn; ++n) {
    if (!on_boundary_[static_cast<size_t>(n)]) continue;
    compact[static_cast<size_t>(n)] = static_cast<int32_t>(boundary_nodes_.size());
    boundary_nodes_.push_back(static_cast<uint32_t>(n));
    boundary_body_.push_back(node_body_[static_cast<size_t>(n)]);
  }
  compact_faces_.resize(faces_.size());
  for (size_t i = 0; i < faces_.size(); ++i) compact_faces_[i] = static_cast<uint32_t>(compact[faces_[i]]);
  for (size_t f = 0; f < faces_.size() / 3; ++f)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = faces_[3 * f + static_cast<size_t>(k)], b = faces_[3 * f + static_cast<size_t>((k + 1) % 3)];
      edge_faces_.push_back({{std::min(a, b), std::max(a, b)}, static_cast<uint32_t>(f)});
    }
  std::sort(edge_faces_.begin(), edge_faces_.end());
}

void FemContact::detect(const std::vector<double>& x, std::vector<Pair>& pairs) const {
  pairs.clear();
  if (faces_.empty()) return;
  // The hash runs on the boundary nodes only (compacted): interior nodes can neither touch nor be touched.
  const size_t nb = boundary_nodes_.size(), nf = faces_.size() / 3;
  std::vector<double> bx(3 * nb);
  for (size_t k = 0; k < nb; ++k)
    for (size_t a = 0; a < 3; ++a) bx[3 * k + a] = x[3 * static_cast<size_t>(boundary_nodes_[k]) + a];
  ContactOptions o;
  o.pairs = options_.self ? ContactPairs::all : ContactPairs::between_objects;
  o.threads = options_.threads;
  const std::vector<VertexTriangleContact> near = vertex_triangle_contacts(bx, compact_faces_, boundary_body_, face_body_, distance_, o);
  if (near.empty()) return;
  // Unit face normals and angle-weighted vertex pseudo-normals (Baerentzen & Aanaes 2005) of the surfaces now.
  std::vector<double> fn(3 * nf), vn(x.size(), 0.0);
  for (size_t f = 0; f < nf; ++f) {
    const uint32_t* c = &faces_[3 * f];
    auto n = face_normal(x, c);
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 0)) continue;
    for (size_t a = 0; a < 3; ++a) fn[3 * f + a] = n[a] / len;
    for (int k = 0; k < 3; ++k) {
      const double* p = &x[3 * static_cast<size_t>(c[k])];
      const double* q = &x[3 * static_cast<size_t>(c[(k + 1) % 3])];
      const double* r = &x[3 * static_cast<size_t>(c[(k + 2) % 3])];
      const double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]}, v[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
      const double lu = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]), lv = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
      if (!(lu > 0 && lv > 0)) continue;
      const double angle = std::acos(std::clamp((u[0] * v[0] + u[1] * v[1] + u[2] * v[2]) / (lu * lv), -1.0, 1.0));
      for (size_t a = 0; a < 3; ++a) vn[3 * static_cast<size_t>(c[k]) + a] += angle * fn[3 * f + a];
    }
  }
  // The pseudo-normal of the feature of face f nearest the node (its interior, an edge or a corner): the
  // sign of (x - q) . N says inside or outside the closed surface, which the face's own plane does not
  // say when q is on its border (a node beside a convex edge is behind the plane yet outside).
  const auto feature_normal = [&](const VertexTriangleContact& c) {
    constexpr double kOnBorder = 1e-9;
    const uint32_t* f = &faces_[3 * static_cast<size_t>(c.triangle)];
    int inside = 0, last = 0;
    for (int k = 0; k < 3; ++k)
      if (c.barycentric[k] > kOnBorder) ++inside, last = k;
    std::array<double, 3> n{fn[3 * c.triangle], fn[3 * c.triangle + 1], fn[3 * c.triangle + 2]};
    if (inside == 1) {
      for (size_t a = 0; a < 3; ++a) n[a] = vn[3 * static_cast<size_t>(f[last]) + a];
    } else if (inside == 2) {
      uint32_t e0 = 0, e1 = 0;
      for (int k = 0, m = 0; k < 3; ++k)
        if (c.barycentric[k] > kOnBorder) (m++ == 0 ? e0 : e1) = f[k];
      const auto key = std::make_pair(std::min(e0, e1), std::max(e0, e1));
      auto it = std::lower_bound(edge_faces_.begin(), edge_faces_.end(), std::make_pair(key, uint32_t{0}));
      n = {0, 0, 0};
      for (; it != edge_faces_.end() && it->first == key; ++it)
        for (size_t a = 0; a < 3; ++a) n[a] += fn[3 * it->second + a];
    }
    return n;
  };
  for (size_t i = 0; i < near.size();) {
    const uint32_t k = near[i].vertex, v = boundary_nodes_[k];
    size_t j = i;
    while (j < near.size() && near[j].vertex == k) ++j;
    const double* xv = &x[3 * static_cast<size_t>(v)];
    // Another body: its face nearest the node decides (inside when behind that feature's pseudo-normal),
    // so a node on the surface of a convex neighbour is not taken for a penetrating one.
    const VertexTriangleContact* other = nullptr;
    for (size_t c = i; c < j; ++c)
      if (face_body_[near[c].triangle] != boundary_body_[k] && (!other || near[c].distance < other->distance)) other = &near[c];
    if (other) {
      const auto n = feature_normal(*other);
      const double d = (xv[0] - other->closest[0]) * n[0] + (xv[1] - other->closest[1]) * n[1] + (xv[2] - other->closest[2]) * n[2];
      if (!(d < 0)) other = nullptr;
    }
    // Its own body (self-contact): a face behind which it lies, facing it (n_v . n < 0), the nearest.
    const VertexTriangleContact* own = nullptr;
    if (options_.self) {
      std::array<double, 3> nv{vn[3 * static_cast<size_t>(v)], vn[3 * static_cast<size_t>(v) + 1], vn[3 * static_cast<size_t>(v) + 2]};
      for (size_t c = i; c < j; ++c) {
        if (face_body_[near[c].triangle] != boundary_body_[k] || !(near[c].signed_distance < 0)) continue;
        const double* nface = &fn[3 * near[c].triangle];
        if (nv[0] * nface[0] + nv[1] * nface[1] + nv[2] * nface[2] >= 0) continue;
        if (!own || near[c].distance < own->distance) own = &near[c];
      }
    }
    const VertexTriangleContact* best = other && (!own || other->distance <= own->distance) ? other : own;
    if (best) pairs.push_back({v, best->triangle, {best->barycentric[0], best->barycentric[1], best->barycentric[2]}});
    i = j;
  }
}

bool FemContact::constraint(const std::vector<double>& x, const Pair& p, std::array<double, 3>& n, double& C) const {
  const uint32_t* f = &faces_[3 * static_cast<size_t>(p.face)];
  n = face_normal(x, f);
  const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  if (!(len > 0)) return false;  // a degenerate face: no normal, no constraint
  for (double& c : n) c /= len;
  C = 0;
  for (size_t a = 0; a < 3; ++a) {
    double q = 0;
    for (size_t k = 0; k < 3; ++k) q += p.b[k] * x[3 * static_cast<size_t>(f[k]) + a];
    C += (x[3 * static_cast<size_t>(p.node) + a] - q) * n[a];
  }
  return true;
}

int64_t FemContact::resolve(const FemModel& model, Real* u, const Real* inv_mass) {
  const size_t n3 = model.nodes.size();
  std::vector<double>& x = scratch_;
  x.resize(n3);
  for (size_t i = 0; i < n3; ++i) x[i] = model.nodes[i] + u[i];
  // Detection every interval_steps steps; in between, the pairs found are enforced again with the
  // current positions (a pair whose constraint holds does nothing).
  if (since_detection_ == 0) detect(x, pairs_);
  since_detection_ = (since_detection_ + 1) % options_.interval_steps;
  const std::vector<Pair>& pairs = pairs_;
  if (pairs.empty()) return 0;
  std::vector<uint8_t>& moved = moved_;
  moved.assign(n3 / 3, 0);
  for (int it = 0; it < options_.iterations; ++it) {
    for (const Pair& p : pairs) {
      const uint32_t* f = &faces_[3 * static_cast<size_t>(p.face)];
      std::array<double, 3> n;
      double C = 0;
      if (!constraint(x, p, n, C) || C >= 0) continue;
      const double wv = inv_mass[p.node];
      double w = wv;
      for (int k = 0; k < 3; ++k) w += p.b[k] * p.b[k] * inv_mass[f[k]];
      if (!(w > 0)) continue;
      const double lambda = -C / w;
      for (int a = 0; a < 3; ++a) x[3 * static_cast<size_t>(p.node) + static_cast<size_t>(a)] += wv * lambda * n[static_cast<size_t>(a)];
      moved[p.node] = 1;
      for (int k = 0; k < 3; ++k) {
        const double s = inv_mass[f[k]] * p.b[k] * lambda;
        for (int a = 0; a < 3; ++a) x[3 * static_cast<size_t>(f[k]) + static_cast<size_t>(a)] -= s * n[static_cast<size_t>(a)];
        moved[f[k]] = 1;
      }
    }
  }
  for (size_t i = 0; i < moved.size(); ++i) {
    if (!moved[i]) continue;
    for (size_t a = 0; a < 3; ++a) u[3 * i + a] = static_cast<Real>(x[3 * i + a] - model.nodes[3 * i + a]);
  }
  return static_cast<int64_t>(pairs.size());
}

double FemContact::deepest_penetration(const FemModel& model, const Real* u) const {
  std::vector<double> x(model.nodes.size());
  for (size_t i = 0; i < x.size(); ++i) x[i] = model.nodes[i] + u[i];
  std::vector<Pair> pairs;
  detect(x, pairs);
  double deepest = 0;
  for (const Pair& p : pairs) {
    std::array<double, 3> n;
    double C = 0;
    if (constraint(x, p, n, C)) deepest = std::max(deepest, -C);
  }
  return deepest;
}

BodySeparation separate_bodies(TetMesh& mesh, bool by_label, const std::vector<HalfSpace>& planes, double gap_mm) {
  BodySeparation out;
  if (!by_label && planes.empty()) return out;
  if (!(std::isfinite(gap_mm) && gap_mm >= 0)) throw InputError(kContactWhere, "gap_mm", "must be finite and >= 0");
  if (gap_mm > 0 && !planes.empty()) {
    // A slab of gap_mm around each plane is taken out (the tets whose centroid is in it), so the bodies
    // start apart: a coincident, jagged seam between two bodies interlocks like a staircase.
    std::vector<int32_t> kept;
    std::vector<uint16_t> labels;
    for (size_t e = 0; e < mesh.tets.size() / 4; ++e) {
      bool in_slab = false;
      for (const HalfSpace& h : planes) {
        const double len = std::sqrt(h.normal[0] * h.normal[0] + h.normal[1] * h.normal[1] + h.normal[2] * h.normal[2]);
        double d = 0;
        for (int a = 0; a < 3; ++a) {
          double c = 0;
          for (int k = 0; k < 4; ++k) c += 0.25 * mesh.nodes[3 * static_cast<size_t>(mesh.tets[4 * e + static_cast<size_t>(k)]) + static_cast<size_t>(a)];
          d += (c - h.point[static_cast<size_t>(a)]) * h.normal[static_cast<size_t>(a)] / len;
        }
        in_slab = in_slab || std::abs(d) < 0.5 * gap_mm;
      }
      if (in_slab) continue;
      kept.insert(kept.end(), mesh.tets.begin() + static_cast<std::ptrdiff_t>(4 * e), mesh.tets.begin() + static_cast<std::ptrdiff_t>(4 * e + 4));
      if (!mesh.tet_labels.empty()) labels.push_back(mesh.tet_labels[e]);
    }
    if (kept.empty()) throw InputError(kContactWhere, "gap_mm", "the slab takes out every tet");
    out.tets_removed = static_cast<int64_t>((mesh.tets.size() - kept.size()) / 4);
    mesh.tets.swap(kept);
    if (!mesh.tet_labels.empty()) mesh.tet_labels.swap(labels);
  }
  const int32_t nn = static_cast<int32_t>(mesh.node_count()), nt = static_cast<int32_t>(mesh.tet_count());
  if (by_label && mesh.tet_labels.size() != static_cast<size_t>(nt)) throw InputError(kContactWhere, "labels", "expected one label per tet");
  for (const HalfSpace& h : planes) {
    const double n2 = h.normal[0] * h.normal[0] + h.normal[1] * h.normal[1] + h.normal[2] * h.normal[2];
    if (!(n2 > 0) || !std::isfinite(n2)) throw InputError(kContactWhere, "planes", "a plane's normal must be finite and not zero");
  }
  if (planes.size() > 16) throw InputError(kContactWhere, "planes", "at most 16 planes");
  // Each tet's region: its label and the sides of the planes its centroid is on.
  std::vector<uint64_t> region(static_cast<size_t>(nt), 0);
  for (int32_t e = 0; e < nt; ++e) {
    uint64_t r = by_label ? mesh.tet_labels[static_cast<size_t>(e)] : 0;
    for (size_t p = 0; p < planes.size(); ++p) {
      double d = 0;
      for (int a = 0; a < 3; ++a) {
        double c = 0;
        for (int k = 0; k < 4; ++k) c += 0.25 * mesh.nodes[3 * static_cast<size_t>(mesh.tets[4 * static_cast<size_t>(e) + static_cast<size_t>(k)]) + static_cast<size_t>(a)];
        d += (c - planes[p].point[static_cast<size_t>(a)]) * planes[p].normal[static_cast<size_t>(a)];
      }
      if (d >= 0) r |= uint64_t{1} << (16 + p);
    }
    region[static_cast<size_t>(e)] = r;
  }
  // Face neighbours.
  std::vector<std::pair<std::array<int32_t, 3>, int32_t>> all;
  for (int32_t e = 0; e < nt; ++e)
    for (const auto& f : kTetOutwardFaces) {
      std::array<int32_t, 3> key{};
      for (int k = 0; k < 3; ++k) key[static_cast<size_t>(k)] = mesh.tets[4 * static_cast<size_t>(e) + static_cast<size_t>(f[k])];
      std::sort(key.begin(), key.end());
      all.emplace_back(key, e);
    }
  std::sort(all.begin(), all.end());
  std::vector<std::pair<int32_t, int32_t>> adjacent;
  for (size_t i = 0; i + 1 < all.size(); ++i)
    if (all[i].first == all[i + 1].first) adjacent.emplace_back(all[i].second, all[i + 1].second);
  // A plane through a tet mesh leaves a jagged seam with islands: tets on one side joined to their side
  // by an edge or a corner only, which would become free fragments, squeezed between the two bodies.
  // Each face-connected piece of one region smaller than 1 % of the mesh (at least 20 tets) joins the
  // region it shares most faces with, until none is left (or 8 rounds).
  for (int round = 0; round < 8; ++round) {
    UnionFind pieces(static_cast<size_t>(nt));
    const auto find = [&](int32_t x) { return pieces.find(x); };
    for (const auto& [a, b] : adjacent)
      if (region[static_cast<size_t>(a)] == region[static_cast<size_t>(b)]) pieces.unite(a, b);
    std::vector<int32_t> size(static_cast<size_t>(nt), 0);
    for (int32_t e = 0; e < nt; ++e) ++size[static_cast<size_t>(find(e))];
    const int32_t small = std::max(20, nt / 100);
    std::map<int32_t, std::map<uint64_t, int32_t>> votes;  // small piece -> neighbouring region -> shared faces
    for (const auto& [a, b] : adjacent) {
      if (region[static_cast<size_t>(a)] == region[static_cast<size_t>(b)]) continue;
      const int32_t ra = find(a), rb = find(b);
      if (size[static_cast<size_t>(ra)] < small) ++votes[ra][region[static_cast<size_t>(b)]];
      if (size[static_cast<size_t>(rb)] < small) ++votes[rb][region[static_cast<size_t>(a)]];
    }
    if (votes.empty()) break;
    std::map<int32_t, uint64_t> to;
    for (const auto& [piece, counts] : votes) {
      uint64_t best = 0;
      int32_t most = -1;
      for (const auto& [r, c] : counts)
        if (c > most) most = c, best = r;
      to[piece] = best;
    }
    for (int32_t e = 0; e < nt; ++e) {
      const auto it = to.find(find(e));
      if (it != to.end()) region[static_cast<size_t>(e)] = it->second;
    }
  }
  // No node is shared between regions: each node used by tets of several regions gets a copy per region
  // beyond the first (in the order of the node's lowest tet in each): the bodies are apart wherever they
  // touch, across faces, edges or corners alike.
  for (const auto& [a, b] : adjacent) out.faces += region[static_cast<size_t>(a)] != region[static_cast<size_t>(b)];
  const size_t nodes_before = mesh.nodes.size() / 3;
  std::vector<std::vector<std::pair<uint64_t, int32_t>>> regions_of(static_cast<size_t>(nn));  // node -> (region, id)
  for (int32_t e = 0; e < nt; ++e)
    for (int k = 0; k < 4; ++k) {
      int32_t& id = mesh.tets[4 * static_cast<size_t>(e) + static_cast<size_t>(k)];
      auto& seen = regions_of[static_cast<size_t>(id)];
      const uint64_t r = region[static_cast<size_t>(e)];
      const auto it = std::find_if(seen.begin(), seen.end(), [&](const auto& x) { return x.first == r; });
      if (it != seen.end()) {
        id = it->second;
        continue;
      }
      if (seen.empty()) {
        seen.emplace_back(r, id);
        continue;
      }
      const int32_t copy = static_cast<int32_t>(mesh.nodes.size() / 3), original = id;
      for (int a = 0; a < 3; ++a) mesh.nodes.push_back(mesh.nodes[3 * static_cast<size_t>(original) + static_cast<size_t>(a)]);
      seen.emplace_back(r, copy);
      id = copy;
    }
  out.nodes_split = static_cast<int64_t>(mesh.nodes.size() / 3 - nodes_before);
  mesh.boundary_faces.clear();
  mesh.face_labels.clear();
  return out;
}

}  // namespace ctsurg::sim
