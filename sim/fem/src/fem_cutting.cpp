#include "ctsurg/sim/fem/fem_cutting.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/base/kernels/segment_triangle_impl.h"
#include "mesh_graph.h"

#include <algorithm>
#include <array>
#include <numeric>
#include <string>

namespace ctsurg::sim {
namespace {

}  // namespace

FemTetSeparation::FemTetSeparation(const FemModel& model)
    : FemTetSeparation(model.order == 1 ? model.tets : std::vector<int32_t>{}, model.order == 1 ? model.node_count() : -1) {}

FemTetSeparation::FemTetSeparation(const std::vector<int32_t>& tets, int32_t node_count) {
  if (node_count < 0) throw InputError("fem cut", "elements", "cutting needs linear (4-node) tets; quadratic elements are not cut");
  if (tets.size() % 4 != 0) throw InputError("fem cut", "elements", "expected #T x 4 node ids");
  for (const int32_t n : tets)
    if (n < 0 || n >= node_count) throw InputError("fem cut", "elements", "node id " + std::to_string(n) + " out of range");
  const int32_t nt = static_cast<int32_t>(tets.size() / 4), nn = node_count;
  std::vector<std::pair<std::array<int32_t, 3>, int32_t>> all;  // (sorted face nodes, element)
  all.reserve(4 * static_cast<size_t>(nt));
  for (int32_t e = 0; e < nt; ++e) {
    const int32_t* t = &tets[4 * static_cast<size_t>(e)];
    for (int skip = 0; skip < 4; ++skip) {
      std::array<int32_t, 3> f{};
      int k = 0;
      for (int a = 0; a < 4; ++a)
        if (a != skip) f[static_cast<size_t>(k++)] = t[a];
      std::sort(f.begin(), f.end());
      all.emplace_back(f, e);
    }
  }
  std::sort(all.begin(), all.end());
  for (size_t i = 0; i + 1 < all.size(); ++i) {
    if (all[i].first != all[i + 1].first) continue;
    if (i + 2 < all.size() && all[i + 2].first == all[i].first) {
      throw InputError("fem cut", "elements", "a face is shared by more than two tets: the mesh is not a manifold");
    }
    faces_.push_back({all[i].second, all[i + 1].second, {all[i].first[0], all[i].first[1], all[i].first[2]}});
    ++i;
  }
  separated_.assign(faces_.size(), 0);
  original_.resize(static_cast<size_t>(nn));
  std::iota(original_.begin(), original_.end(), 0);
  std::vector<std::pair<int32_t, int32_t>> node_tet, node_face;
  for (int32_t e = 0; e < nt; ++e)
    for (int a = 0; a < 4; ++a) node_tet.emplace_back(tets[4 * static_cast<size_t>(e) + static_cast<size_t>(a)], e);
  for (size_t f = 0; f < faces_.size(); ++f)
    for (const int32_t n : faces_[f].nodes) node_face.emplace_back(n, static_cast<int32_t>(f));
  build_csr(nn, node_tet, tet_offsets_, tet_list_);
  build_csr(nn, node_face, face_offsets_, face_list_);
}

int64_t FemTetSeparation::faces_separated() const {
  return std::count(separated_.begin(), separated_.end(), uint8_t{1});
}

FemCutResult FemTetSeparation::cut(std::vector<int32_t>& tets, int32_t node_count, const std::vector<double>& positions,
                                   const Triangle& blade) {
  if (static_cast<size_t>(node_count) != original_.size()) {
    throw InputError("fem cut", "nodes", "the mesh has " + std::to_string(node_count) + " nodes; the separation knows " +
                                             std::to_string(original_.size()) + " (every cut must go through this object)");
  }
  if (positions.size() != 3 * static_cast<size_t>(node_count)) throw InputError("fem cut", "positions", "expected #N x 3");
  TriangleView t{};
  for (int c = 0; c < 3; ++c) {
    t.a[c] = blade.a[static_cast<size_t>(c)];
    t.b[c] = blade.b[static_cast<size_t>(c)];
    t.c[c] = blade.c[static_cast<size_t>(c)];
  }
  const auto centroid = [&](int32_t e, double* c) {
    c[0] = c[1] = c[2] = 0;
    for (int a = 0; a < 4; ++a) {
      const size_t n = static_cast<size_t>(tets[4 * static_cast<size_t>(e) + static_cast<size_t>(a)]);
      for (int k = 0; k < 3; ++k) c[k] += 0.25 * positions[3 * n + static_cast<size_t>(k)];
    }
  };
  FemCutResult r;
  std::vector<int32_t> touched;  // original nodes of newly separated faces
  for (size_t f = 0; f < faces_.size(); ++f) {
    if (separated_[f]) continue;
    double p[3], q[3];
    centroid(faces_[f].a, p);
    centroid(faces_[f].b, q);
    if (!segment_crosses_triangle(p, q, t)) continue;
    separated_[f] = 1;
    ++r.faces_separated;
    touched.insert(touched.end(), faces_[f].nodes, faces_[f].nodes + 3);
  }
  split(tets, node_count, touched, r);
  return r;
}

void FemTetSeparation::split(std::vector<int32_t>& tets, int32_t node_count, std::vector<int32_t>& touched, FemCutResult& r) {
  std::sort(touched.begin(), touched.end());
  touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
  for (const int32_t n : touched) {
    const int32_t t0 = tet_offsets_[static_cast<size_t>(n)], t1 = tet_offsets_[static_cast<size_t>(n) + 1];
    const auto local = [&](int32_t e) {  // index of element e in n's (sorted) element list
      return static_cast<int32_t>(std::lower_bound(tet_list_.begin() + t0, tet_list_.begin() + t1, e) - (tet_list_.begin() + t0));
    };
    UnionFind groups(static_cast<size_t>(t1 - t0));
    for (int32_t k = face_offsets_[static_cast<size_t>(n)]; k < face_offsets_[static_cast<size_t>(n) + 1]; ++k) {
      const Face& f = faces_[static_cast<size_t>(face_list_[static_cast<size_t>(k)])];
      if (!separated_[static_cast<size_t>(face_list_[static_cast<size_t>(k)])]) groups.unite(local(f.a), local(f.b));
    }
    // Each group (in the order of its lowest element) keeps the id its elements use, unless an earlier
    // group took it: then a new node, copied from that id.
    std::vector<int32_t> id_of_root(static_cast<size_t>(t1 - t0), -1);
    std::vector<int32_t> claimed;  // current ids already kept by a group
    for (int32_t k = 0; k < t1 - t0; ++k) {
      const int32_t root = groups.find(k);
      if (id_of_root[static_cast<size_t>(root)] >= 0) continue;
      const int32_t e = tet_list_[static_cast<size_t>(t0 + root)];
      int32_t current = -1;
      for (int a = 0; a < 4; ++a) {
        const int32_t id = tets[4 * static_cast<size_t>(e) + static_cast<size_t>(a)];
        if (original_[static_cast<size_t>(id)] == n) current = id;
      }
      if (std::find(claimed.begin(), claimed.end(), current) == claimed.end()) {
        claimed.push_back(current);
        id_of_root[static_cast<size_t>(root)] = current;
      } else {
        const int32_t fresh = node_count + static_cast<int32_t>(r.new_node_parent.size());
        r.new_node_parent.push_back(current);
        original_.push_back(n);
        id_of_root[static_cast<size_t>(root)] = fresh;
      }
    }
    for (int32_t k = 0; k < t1 - t0; ++k) {
      const int32_t e = tet_list_[static_cast<size_t>(t0 + k)], id = id_of_root[static_cast<size_t>(groups.find(k))];
      for (int a = 0; a < 4; ++a) {
        int32_t& slot = tets[4 * static_cast<size_t>(e) + static_cast<size_t>(a)];
        if (original_[static_cast<size_t>(slot)] == n) slot = id;
      }
    }
  }
}

FemCutResult FemTetSeparation::separate_where(std::vector<int32_t>& tets, int32_t node_count,
                                              const std::function<bool(int32_t a, int32_t b)>& separate) {
  if (static_cast<size_t>(node_count) != original_.size()) {
    throw InputError("fem cut", "nodes", "the mesh has " + std::to_string(node_count) + " nodes; the separation knows " +
                                             std::to_string(original_.size()) + " (every cut must go through this object)");
  }
  FemCutResult r;
  std::vector<int32_t> touched;
  for (size_t f = 0; f < faces_.size(); ++f) {
    if (separated_[f] || !separate(faces_[f].a, faces_[f].b)) continue;
    separated_[f] = 1;
    ++r.faces_separated;
    touched.insert(touched.end(), faces_[f].nodes, faces_[f].nodes + 3);
  }
  split(tets, node_count, touched, r);
  return r;
}

int32_t fem_mesh_pieces(const std::vector<int32_t>& tets, int32_t node_count, std::vector<int32_t>& piece_of_node) {
  UnionFind nodes(static_cast<size_t>(node_count));
  for (size_t e = 0; e + 3 < tets.size(); e += 4)
    for (int a = 1; a < 4; ++a) nodes.unite(tets[e], tets[e + static_cast<size_t>(a)]);
  std::vector<uint8_t> used(static_cast<size_t>(node_count), 0);
  for (const int32_t n : tets) used[static_cast<size_t>(n)] = 1;
  piece_of_node.assign(static_cast<size_t>(node_count), -1);
  std::vector<int32_t> piece_of_root(static_cast<size_t>(node_count), -1);
  int32_t pieces = 0;
  for (int32_t n = 0; n < node_count; ++n) {
    if (!used[static_cast<size_t>(n)]) continue;
    int32_t& p = piece_of_root[static_cast<size_t>(nodes.find(n))];
    if (p < 0) p = pieces++;
    piece_of_node[static_cast<size_t>(n)] = p;
  }
  return pieces;
}

std::vector<uint32_t> fem_boundary_faces(const std::vector<int32_t>& tets) {
  const size_t nt = tets.size() / 4;
  std::vector<std::pair<std::array<int32_t, 3>, uint32_t>> keys;  // sorted corners, 4 e + f
  keys.reserve(4 * nt);
  for (size_t e = 0; e < nt; ++e)
    for (uint32_t f = 0; f < 4; ++f) {
      std::array<int32_t, 3> k{};
      for (size_t c = 0; c < 3; ++c) k[c] = tets[4 * e + static_cast<size_t>(kTetOutwardFaces[f][c])];
      std::sort(k.begin(), k.end());
      keys.emplace_back(k, static_cast<uint32_t>(4 * e + f));
    }
  std::sort(keys.begin(), keys.end());
  std::vector<uint8_t> single(4 * nt, 0);
  for (size_t i = 0; i < keys.size();) {
    size_t j = i + 1;
    while (j < keys.size() && keys[j].first == keys[i].first) ++j;
    if (j == i + 1) single[keys[i].second] = 1;
    i = j;
  }
  std::vector<uint32_t> faces;
  for (size_t ef = 0; ef < single.size(); ++ef) {
    if (!single[ef]) continue;
    for (size_t c = 0; c < 3; ++c) faces.push_back(static_cast<uint32_t>(tets[4 * (ef / 4) + static_cast<size_t>(kTetOutwardFaces[ef % 4][c])]));
  }
  return faces;
}

}  // namespace ctsurg::sim
