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

constexpr const char* kWhere = "fem contact";

// The faces of a positively oriented tet (0, 1, 2, 3), wound outwards: opposite corner 3, 2, 0, 1.
constexpr int kOutwardFaces[4][3] = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};

std::array<double, 3> face_normal(const std::vector<double>& x, const uint32_t* f) {  // not normalised: 2 x area
  const double* a = &x[3 * static_cast<size_t>(f[0])];
  const double* b = &x[3 * static_cast<size_t>(f[1])];
  const double* c = &x[3 * static_cast<size_t>(f[2])];
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  return {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
}

}  // namespace

FemContact::FemContact(const FemModel& model, const FemContactOptions& options) : options_(options) {
  if (model.order != 1) throw InputError(kWhere, "elements", "contact runs on linear (4-node) tets");
  if (options.iterations < 1 || options.iterations > 100) throw InputError(kWhere, "iterations", "must be 1 .. 100");
  if (options.interval_steps < 1 || options.interval_steps > 1000) throw InputError(kWhere, "interval_steps", "must be 1 .. 1000");
  if (!(std::isfinite(options.distance_mm) && options.distance_mm >= 0)) throw InputError(kWhere, "distance_mm", "must be finite and >= 0");
  const int32_t nt = model.tet_count(), nn = model.node_count();
  std::map<std::array<int32_t, 3>, int> count;
  for (int32_t e = 0; e < nt; ++e)
    for (const auto& f : kOutwardFaces) {
      std::array<int32_t, 3> key{};
      for (int k = 0; k < 3; ++k) key[static_cast<size_t>(k)] = model.tets[4 * static_cast<size_t>(e) + static_cast<size_t>(f[k])];
      std::sort(key.begin(), key.end());
      ++count[key];
    }
  std::vector<int32_t> body;
  bodies_ = fem_mesh_pieces(model.tets, nn, body);
  on_boundary_.assign(static_cast<size_t>(nn), 0);
  node_body_.assign(static_cast<size_t>(nn), 0);
  for (int32_t n = 0; n < nn; ++n) node_body_[static_cast<size_t>(n)] = static_cast<uint32_t>(std::max(body[static_cast<size_t>(n)], 0));
  double edge_sum = 0;
  int64_t edges = 0;
  for (int32_t e = 0; e < nt; ++e)
    for (const auto& f : kOutwardFaces) {
      std::array<int32_t, 3> key{}, wound{};
      for (int k = 0; k < 3; ++k) wound[static_cast<size_t>(k)] = key[static_cast<size_t>(k)] = model.tets[4 * static_cast<size_t>(e) + static_cast<size_t>(f[k])];
      std::sort(key.begin(), key.end());
      if (count[key] != 1) continue;
      for (int k = 0; k < 3; ++k) {
        faces_.push_back(static_cast<uint32_t>(wound[static_cast<size_t>(k)]));
        on_boundary_[static_cast<size_t>(wound[static_cast<size_t>(k)])] = 1;
        const double* p = &model.nodes[3 * static_cast<size_t>(wound[static_cast<size_t>(k)])];
        const double* q = &model.nodes[3 * static_cast<size_t>(wound[static_cast<size_t>((k + 1) % 3)])];
        edge_sum += std::sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
        ++edges;
      }
      face_body_.push_back(node_body_[static_cast<size_t>(wound[0])]);
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
  std::vector<std::pair<int32_t, int32_t>> node_face;
  for (size_t f = 0; f < faces_.size() / 3; ++f)
    for (int k = 0; k < 3; ++k) node_face.emplace_back(static_cast<int32_t>(faces_[3 * f + static_cast<size_t>(k)]), static_cast<int32_t>(f));
  build_csr(nn, node_face, node_faces_offsets_, node_faces_);
}

void FemContact::detect(const std::vector<double>& x, std::vector<Pair>& pairs) const {
  pairs.clear();
  if (faces_.empty()) return;
  // The boundary nodes only (the faces' corners), compacted: the hash sees the surface, not the volume.
  const size_t nb = boundary_nodes_.size();
  std::vector<double> bx(3 * nb);
  for (size_t k = 0; k < nb; ++k)
    for (size_t a = 0; a < 3; ++a) bx[3 * k + a] = x[3 * static_cast<size_t>(boundary_nodes_[k]) + a];
  ContactOptions o;
  o.pairs = options_.self ? ContactPairs::all : ContactPairs::between_objects;
  o.threads = options_.threads;
  const std::vector<VertexTriangleContact> near = vertex_triangle_contacts(bx, compact_faces_, boundary_body_, face_body_, distance_, o);
  for (size_t i = 0; i < near.size();) {
    const uint32_t k = near[i].vertex, v = boundary_nodes_[k];
    size_t j = i;
    while (j < near.size() && near[j].vertex == k) ++j;
    std::array<double, 3> nv{0, 0, 0};
    for (int32_t q = node_faces_offsets_[v]; q < node_faces_offsets_[v + 1]; ++q) {
      const auto n = face_normal(x, &faces_[3 * static_cast<size_t>(node_faces_[static_cast<size_t>(q)])]);
      for (int a = 0; a < 3; ++a) nv[static_cast<size_t>(a)] += n[static_cast<size_t>(a)];
    }
    // The nearest face it is behind: of another body, or of its own body facing it (proximity to one's
    // own surface where it curves is not contact).
    const VertexTriangleContact* best = nullptr;
    for (size_t c = i; c < j; ++c) {
      if (!(near[c].signed_distance < 0)) continue;
      if (face_body_[near[c].triangle] == boundary_body_[k]) {
        const auto nf = face_normal(x, &faces_[3 * static_cast<size_t>(near[c].triangle)]);
        if (nv[0] * nf[0] + nv[1] * nf[1] + nv[2] * nf[2] >= 0) continue;
      }
      if (!best || near[c].distance < best->distance) best = &near[c];
    }
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
  if (!(std::isfinite(gap_mm) && gap_mm >= 0)) throw InputError(kWhere, "gap_mm", "must be finite and >= 0");
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
    if (kept.empty()) throw InputError(kWhere, "gap_mm", "the slab takes out every tet");
    out.tets_removed = static_cast<int64_t>((mesh.tets.size() - kept.size()) / 4);
    mesh.tets.swap(kept);
    if (!mesh.tet_labels.empty()) mesh.tet_labels.swap(labels);
  }
  const int32_t nn = static_cast<int32_t>(mesh.node_count()), nt = static_cast<int32_t>(mesh.tet_count());
  if (by_label && mesh.tet_labels.size() != static_cast<size_t>(nt)) throw InputError(kWhere, "labels", "expected one label per tet");
  for (const HalfSpace& h : planes) {
    const double n2 = h.normal[0] * h.normal[0] + h.normal[1] * h.normal[1] + h.normal[2] * h.normal[2];
    if (!(n2 > 0) || !std::isfinite(n2)) throw InputError(kWhere, "planes", "a plane's normal must be finite and not zero");
  }
  if (planes.size() > 16) throw InputError(kWhere, "planes", "at most 16 planes");
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
    for (const auto& f : kOutwardFaces) {
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
