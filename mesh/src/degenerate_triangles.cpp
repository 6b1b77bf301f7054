#include "ctsurg/mesh/degenerate_triangles.h"

#include "ctsurg/core/error.h"

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <numeric>

namespace ctsurg {

namespace {

using Vec = Eigen::Vector3d;

constexpr double kCapAngleDegrees = 150.0;
constexpr int kMaxPasses = 32;

// Interior angles (degrees) of triangle p, at corners 0, 1, 2; atan2 keeps them accurate near 0 and
// 180 degrees. A corner with a zero-length edge gets 0.
std::array<double, 3> angles_deg(const Vec p[3]) {
  std::array<double, 3> a{};
  for (int c = 0; c < 3; ++c) {
    const Vec e1 = p[(c + 1) % 3] - p[c], e2 = p[(c + 2) % 3] - p[c];
    a[static_cast<std::size_t>(c)] = std::atan2(e1.cross(e2).norm(), e1.dot(e2)) * 180.0 / std::numbers::pi;
  }
  return a;
}

double min_angle_deg(const Vec p[3]) {
  const auto a = angles_deg(p);
  return std::min({a[0], a[1], a[2]});
}

Degeneracy classify(const uint32_t id[3], const Vec p[3], double h) {
  if (id[0] == id[1] || id[1] == id[2] || id[0] == id[2]) return Degeneracy::kRepeatedIndex;
  // p holds float32 values widened to double, so equal doubles are equal floats.
  if (p[0] == p[1] || p[1] == p[2] || p[0] == p[2]) return Degeneracy::kCoincidentCorners;
  if (0.5 * (p[1] - p[0]).cross(p[2] - p[0]).norm() < kMinAreaFraction * h * h) return Degeneracy::kTinyArea;
  if (min_angle_deg(p) < kMinAngleDegrees) return Degeneracy::kSliver;
  return Degeneracy::kNone;
}

void check_cell(double cell_mm) {
  if (!(cell_mm > 0.0 && std::isfinite(cell_mm))) {
    throw InputError("mesh", "cell size", "must be a positive finite length in mm, got " + std::to_string(cell_mm));
  }
}

// The working mesh of remove_degenerate_triangles: positions (moved only by relax()), triangles with
// an alive flag, and each vertex's incident live triangles.
class Repairer {
 public:
  Repairer(const SurfaceMesh& mesh, double h)
      : h_(h), tiny2_(2.0 * kMinAreaFraction * h * h), merge_(kMergeDistanceFraction * h),
        max_collapse_(kMaxCollapseFraction * h),
        x_(mesh.vertices.begin(), mesh.vertices.end()), tri_(mesh.triangles),
        alive_(static_cast<std::size_t>(mesh.triangle_count()), 1), vt_(static_cast<std::size_t>(mesh.vertex_count())),
        origin_(vt_.size()) {
    for (uint32_t t = 0; t < alive_.size(); ++t)
      for (int c = 0; c < 3; ++c) vt_[corner(t, c)].push_back(t);
    std::iota(origin_.begin(), origin_.end(), 0u);
  }

  int64_t handles_cut = 0, tents_removed = 0, relaxed = 0;
  double longest_collapse = 0.0;  // mm

  // Step 1: collapse every edge shorter than the merge distance (keeping the lower index first).
  int64_t merge() {
    int64_t merged = 0;
    for (int pass = 0; pass < kMaxPasses; ++pass) {
      int64_t n = 0;
      for (uint32_t t = 0; t < alive_.size(); ++t)
        for (int c = 0; c < 3 && alive_[t]; ++c) {
          const uint32_t a = corner(t, c), b = corner(t, (c + 1) % 3);
          if (a == b || (P(a) - P(b)).norm() >= merge_) continue;
          if (collapse_edge(a, b)) ++n;
        }
      merged += n;
      if (n == 0) break;
    }
    return merged;
  }

  // Step 2: needles collapsed, caps flipped, until a pass changes nothing.
  void repair(int64_t& collapsed, int64_t& flipped) {
    for (int pass = 0; pass < kMaxPasses; ++pass) {
      bool changed = false;
      for (uint32_t t = 0; t < alive_.size(); ++t) {
        if (!alive_[t] || degeneracy(t) == Degeneracy::kNone) continue;
        const uint32_t id[3] = {corner(t, 0), corner(t, 1), corner(t, 2)};
        const Vec p[3] = {P(id[0]), P(id[1]), P(id[2])};
        // Edge c joins corners c and c + 1; order the edges by length.
        std::array<int, 3> e = {0, 1, 2};
        std::array<double, 3> len{};
        for (int c = 0; c < 3; ++c) len[static_cast<std::size_t>(c)] = (p[(c + 1) % 3] - p[c]).norm();
        std::stable_sort(e.begin(), e.end(), [&](int a, int b) { return len[std::size_t(a)] < len[std::size_t(b)]; });
        const auto ang = angles_deg(p);
        const bool cap = std::max({ang[0], ang[1], ang[2]}) >= kCapAngleDegrees;
        const auto try_collapse = [&](int edge) {
          const uint32_t a = id[edge], b = id[(edge + 1) % 3];
          if (a == b) return false;
          if (collapse_edge(a, b)) {
            ++collapsed;
            return true;
          }
          return false;
        };
        const auto try_flip = [&](int edge) {
          if (flip(t, edge)) {
            ++flipped;
            return true;
          }
          return false;
        };
        const bool done = cap ? (try_flip(e[2]) || try_collapse(e[0]) || try_collapse(e[1]) || try_flip(e[1]) ||
                                 try_flip(e[0]) || try_collapse(e[2]))
                              : (try_collapse(e[0]) || try_flip(e[2]) || try_collapse(e[1]) || try_flip(e[1]) ||
                                 try_flip(e[0]) || try_collapse(e[2]));
        changed = changed || done;
      }
      if (!changed) break;
    }
  }

  // Optional step: each vertex of a triangle still degenerate (the cap's apex first) may move to the
  // mean of its one-ring projected on the ring's tangent plane, when that folds no triangle and
  // leaves its fan fewer degenerate triangles (or as many and a larger smallest angle). Returns the
  // vertices moved.
  int64_t relax() {
    int64_t moved = 0;
    for (int pass = 0; pass < kMaxPasses; ++pass) {
      int64_t n = 0;
      for (uint32_t t = 0; t < alive_.size(); ++t) {
        if (!alive_[t] || degeneracy(t) == Degeneracy::kNone) continue;
        const uint32_t id[3] = {corner(t, 0), corner(t, 1), corner(t, 2)};
        const Vec p[3] = {P(id[0]), P(id[1]), P(id[2])};
        const auto ang = angles_deg(p);
        std::array<int, 3> order = {0, 1, 2};
        std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return ang[std::size_t(a)] > ang[std::size_t(b)]; });
        for (const int c : order)
          if (relax_vertex(id[c])) {
            ++n;
            break;
          }
      }
      moved += n;
      if (n == 0) break;
    }
    relaxed += moved;
    return moved;
  }

  // Step 3: drop the connected components (through shared vertices) whose triangles are all
  // degenerate, or that still hold a degenerate triangle and have less area than one cell face or
  // at most 4 vertices (a tetrahedron has no valid collapse or flip).
  int64_t drop_degenerate_components() {
    std::vector<uint32_t> parent(vt_.size());
    std::iota(parent.begin(), parent.end(), 0u);
    const auto find = [&](uint32_t v) {
      while (parent[v] != v) v = parent[v] = parent[parent[v]];
      return v;
    };
    for (uint32_t t = 0; t < alive_.size(); ++t)
      if (alive_[t])
        for (int c = 1; c < 3; ++c) {
          const uint32_t a = find(corner(t, 0)), b = find(corner(t, c));
          if (a != b) parent[std::max(a, b)] = std::min(a, b);
        }
    std::vector<char> has_good(vt_.size(), 0), has_bad(vt_.size(), 0);
    std::vector<double> area2(vt_.size(), 0.0);
    std::vector<int64_t> vertices(vt_.size(), 0);
    for (uint32_t t = 0; t < alive_.size(); ++t)
      if (alive_[t]) {
        const uint32_t r = find(corner(t, 0));
        (degeneracy(t) == Degeneracy::kNone ? has_good : has_bad)[r] = 1;
        area2[r] += normal(t).norm();
      }
    for (uint32_t v = 0; v < vt_.size(); ++v)
      if (!vt_[v].empty()) ++vertices[find(v)];
    std::vector<char> drop(vt_.size(), 0);
    int64_t dropped = 0;
    for (uint32_t v = 0; v < vt_.size(); ++v) {
      drop[v] = has_bad[v] && (!has_good[v] || area2[v] < 2.0 * h_ * h_ || vertices[v] <= 4);
      dropped += drop[v];
    }
    for (uint32_t t = 0; t < alive_.size(); ++t)
      if (alive_[t] && drop[find(corner(t, 0))]) alive_[t] = 0;
    return dropped;
  }

  // Writes the live triangles into `mesh`, drops unreferenced vertices and carries every per-vertex
  // array along.
  void write(SurfaceMesh& mesh) const {
    const std::size_t nv = vt_.size(), nv_in = static_cast<std::size_t>(mesh.vertex_count());
    std::vector<uint32_t> remap(nv, UINT32_MAX);
    std::vector<uint32_t> tris;
    tris.reserve(tri_.size());
    for (uint32_t t = 0; t < alive_.size(); ++t)
      if (alive_[t])
        for (int c = 0; c < 3; ++c) remap[corner(t, c)] = 0;
    uint32_t next = 0;
    std::vector<uint32_t> kept;
    for (uint32_t v = 0; v < nv; ++v)
      if (remap[v] == 0) {
        remap[v] = next++;
        kept.push_back(v);
      }
    for (uint32_t t = 0; t < alive_.size(); ++t)
      if (alive_[t])
        for (int c = 0; c < 3; ++c) tris.push_back(remap[corner(t, c)]);
    mesh.triangles = std::move(tris);
    const auto carry = [&](auto& a) {
      if (nv_in == 0 || a.empty() || a.size() % nv_in != 0) return;
      const std::size_t w = a.size() / nv_in;
      std::remove_reference_t<decltype(a)> out(w * kept.size());
      for (std::size_t i = 0; i < kept.size(); ++i)
        std::copy_n(a.begin() + static_cast<std::ptrdiff_t>(w * origin_[kept[i]]), w,
                    out.begin() + static_cast<std::ptrdiff_t>(w * i));
      a = std::move(out);
    };
    carry(mesh.vertices);
    for (std::size_t i = 0; i < kept.size(); ++i)  // relaxed vertices moved; the others keep their floats
      for (std::size_t a = 0; a < 3; ++a) mesh.vertices[3 * i + a] = static_cast<float>(x_[3 * std::size_t{kept[i]} + a]);
    carry(mesh.normals);
    carry(mesh.grid_cell);
    carry(mesh.grid_weights);
    carry(mesh.nearest_node);
    carry(mesh.uvs);
    carry(mesh.tangents);
    carry(mesh.source_vertex);
  }

 private:
  double h_, tiny2_, merge_, max_collapse_;  // cell size; twice the smallest trusted area; merge and
                                             // longest collapse distances
  std::vector<double> x_;
  std::vector<uint32_t> tri_;
  std::vector<char> alive_;
  std::vector<std::vector<uint32_t>> vt_;
  std::vector<uint32_t> origin_;  // the input vertex each vertex copies (cut_handle() adds copies)

  uint32_t corner(uint32_t t, int c) const { return tri_[3 * std::size_t{t} + static_cast<std::size_t>(c)]; }
  Vec P(uint32_t v) const { return {x_[3 * std::size_t{v}], x_[3 * std::size_t{v} + 1], x_[3 * std::size_t{v} + 2]}; }
  Vec normal(uint32_t a, uint32_t b, uint32_t c) const { return (P(b) - P(a)).cross(P(c) - P(a)); }
  Vec normal(uint32_t t) const { return normal(corner(t, 0), corner(t, 1), corner(t, 2)); }
  bool has(uint32_t t, uint32_t v) const { return corner(t, 0) == v || corner(t, 1) == v || corner(t, 2) == v; }

  Degeneracy degeneracy(uint32_t t) const {
    const uint32_t id[3] = {corner(t, 0), corner(t, 1), corner(t, 2)};
    const Vec p[3] = {P(id[0]), P(id[1]), P(id[2])};
    return classify(id, p, h_);
  }

  // Sorted, unique vertices sharing a live triangle with u.
  std::vector<uint32_t> neighbours(uint32_t u) const {
    std::vector<uint32_t> n;
    for (const uint32_t t : vt_[u])
      for (int c = 0; c < 3; ++c)
        if (corner(t, c) != u) n.push_back(corner(t, c));
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
    return n;
  }

  std::vector<uint32_t> edge_triangles(uint32_t u, uint32_t v) const {
    std::vector<uint32_t> e;
    for (const uint32_t t : vt_[u])
      if (has(t, v)) e.push_back(t);
    return e;
  }

  // A vertex with an edge that is not shared by exactly two triangles: a border of an open surface
  // (or a non-manifold edge); such vertices are not moved.
  bool on_border(uint32_t u) const {
    for (const uint32_t w : neighbours(u))
      if (edge_triangles(u, w).size() != 2) return true;
    return false;
  }

  uint32_t third(uint32_t t, uint32_t a, uint32_t b) const {
    for (int c = 0; c < 3; ++c)
      if (corner(t, c) != a && corner(t, c) != b) return corner(t, c);
    return a;
  }

  void unlink(uint32_t t, uint32_t v) {
    auto& l = vt_[v];
    l.erase(std::remove(l.begin(), l.end(), t), l.end());
  }

  // Collapses edge (a, b) into its lower index, or else into the other. Where the link condition
  // fails because of a 3-cycle (a, b, w) that is not a face, the surface passes through the edge
  // twice: a handle whose width there is at most the edge's length (it touches itself at a node
  // exactly at the isovalue, or nearly). Collapsing would pinch it into a non-manifold vertex, so the
  // handle is cut along the cycle first (cut_handle); the collapse that follows removes both caps
  // with the edge, so the surface moves no more than a collapse moves it anyway.
  bool collapse_edge(uint32_t a, uint32_t b) {
    const uint32_t lo = std::min(a, b), hi = std::max(a, b);
    if ((P(a) - P(b)).norm() > max_collapse_) return false;
    for (int attempt = 0; attempt < 8; ++attempt) {
      std::vector<uint32_t> extra;
      uint32_t tent = UINT32_MAX;
      if (collapse(hi, lo, &extra, &tent) || collapse(lo, hi)) return true;
      bool changed = false;
      for (const uint32_t w : extra)
        if (cut_handle(lo, hi, w)) {
          ++handles_cut;
          changed = true;
          break;
        }
      if (!changed && tent != UINT32_MAX && remove_tent(tent)) {
        ++tents_removed;
        changed = true;
      }
      if (!changed) return false;
    }
    return false;
  }

  // Cuts the surface along the 3-cycle u -> v -> w -> u (three edges, no face) and closes both sides
  // with a triangle: the loop's vertices are duplicated for the triangles on its left (walking each
  // vertex's fan counter-clockwise from the outgoing loop edge to the incoming one), which get the
  // cap (u', w', v'); the right side gets (u, v, w). Both caps have the loop's (tiny) area, and the
  // mesh stays a closed oriented 2-manifold (one handle fewer, or one more component).
  bool cut_handle(uint32_t u, uint32_t v, uint32_t w) {
    for (const uint32_t t : vt_[u])
      if (has(t, v) && has(t, w)) return false;
    // A loop vertex on a border is fine as long as its walk below closes without meeting the border
    // (a missing next triangle refuses the cut).
    const uint32_t loop[3] = {u, v, w};
    std::vector<uint32_t> side[3];
    for (int i = 0; i < 3; ++i) {
      const uint32_t p = loop[i], next = loop[(i + 1) % 3], prev = loop[(i + 2) % 3];
      uint32_t b = next;
      bool closed = false;
      for (std::size_t step = 0; step < vt_[p].size() && !closed; ++step) {
        uint32_t found = UINT32_MAX, c = 0;
        for (const uint32_t t : vt_[p])
          for (int k = 0; k < 3; ++k)
            if (corner(t, k) == p && corner(t, (k + 1) % 3) == b) {
              found = t;
              c = corner(t, (k + 2) % 3);
            }
        if (found == UINT32_MAX) return false;
        side[i].push_back(found);
        closed = c == prev;
        b = c;
      }
      if (!closed || side[i].size() >= vt_[p].size()) return false;
    }
    uint32_t copy[3];
    for (int i = 0; i < 3; ++i) {
      copy[i] = static_cast<uint32_t>(vt_.size());
      for (std::size_t a = 0; a < 3; ++a) x_.push_back(x_[3 * std::size_t{loop[i]} + a]);
      origin_.push_back(origin_[loop[i]]);
      vt_.emplace_back();
    }
    for (int i = 0; i < 3; ++i)
      for (const uint32_t t : side[i]) {
        for (int k = 0; k < 3; ++k)
          if (corner(t, k) == loop[i]) tri_[3 * std::size_t{t} + static_cast<std::size_t>(k)] = copy[i];
        unlink(t, loop[i]);
        vt_[copy[i]].push_back(t);
      }
    add_triangle(copy[0], copy[2], copy[1]);
    add_triangle(u, v, w);
    for (const uint32_t p : {u, v, w, copy[0], copy[1], copy[2]}) std::sort(vt_[p].begin(), vt_[p].end());
    return true;
  }

  double fan_min_angle(uint32_t v) const {
    double m = 180.0;
    for (const uint32_t t : vt_[v]) {
      const Vec p[3] = {P(corner(t, 0)), P(corner(t, 1)), P(corner(t, 2))};
      m = std::min(m, min_angle_deg(p));
    }
    return m;
  }

  bool relax_vertex(uint32_t v) {
    if (vt_[v].empty() || on_border(v)) return false;
    Vec ring = Vec::Zero(), mean = Vec::Zero();
    for (const uint32_t t : vt_[v]) ring += normal(t);
    const std::vector<uint32_t> n = neighbours(v);
    for (const uint32_t w : n) mean += P(w);
    mean /= double(n.size());
    if (!(ring.norm() > tiny2_)) return false;
    const Vec u = ring.normalized();
    const Vec old = P(v);
    const Vec target = old + (mean - old) - (mean - old).dot(u) * u;
    const auto bad = [&] {
      int64_t k = 0;
      for (const uint32_t t : vt_[v]) k += degeneracy(t) != Degeneracy::kNone;
      return k;
    };
    const int64_t bad_before = bad();
    const double before = fan_min_angle(v);
    for (std::size_t a = 0; a < 3; ++a) x_[3 * std::size_t{v} + a] = static_cast<float>(target[static_cast<Eigen::Index>(a)]);
    const int64_t bad_after = bad();
    bool ok = bad_after < bad_before || (bad_after == bad_before && fan_min_angle(v) > before);
    for (const uint32_t t : vt_[v]) ok = ok && normal(t).dot(ring) > 0.0;
    if (!ok)
      for (std::size_t a = 0; a < 3; ++a) x_[3 * std::size_t{v} + a] = old[static_cast<Eigen::Index>(a)];
    return ok;
  }

  // Removes a vertex o of valence 3 (a tent over the triangle of its neighbours a, b, c), replacing
  // its three triangles by (a, b, c) in the ring's orientation; refused on a border, when (a, b, c)
  // is already a face, when a neighbour would keep fewer than 3 neighbours, or when o is farther than
  // the longest collapse from the triangle (the surface moves by that distance at most) unless the
  // tetrahedron (o, a, b, c) has no volume (below 1e-6 h^3: a fin of two coincident triangles). The
  // new triangle's normal is the ring's area vector, so it cannot turn over.
  bool remove_tent(uint32_t o) {
    if (vt_[o].size() != 3 || on_border(o)) return false;
    const std::vector<uint32_t> n = neighbours(o);
    if (n.size() != 3) return false;
    // The ring edge of each triangle (o, x, y): x -> y; chain them into a -> b -> c.
    uint32_t next[3] = {0, 0, 0}, from[3] = {0, 0, 0};
    for (int i = 0; i < 3; ++i) {
      const uint32_t t = vt_[o][static_cast<std::size_t>(i)];
      int k = 0;
      while (corner(t, k) != o) ++k;
      from[i] = corner(t, (k + 1) % 3);
      next[i] = corner(t, (k + 2) % 3);
    }
    const uint32_t a = from[0], b = next[0];
    uint32_t c = UINT32_MAX;
    for (int i = 0; i < 3; ++i)
      if (from[i] == b) c = next[i];
    if (c == UINT32_MAX || c == a || c == b) return false;
    for (const uint32_t t : vt_[a])
      if (has(t, b) && has(t, c)) return false;
    for (const uint32_t x : {a, b, c})
      if (neighbours(x).size() <= 3) return false;
    // Near the triangle, or of no volume (a fin of two coincident triangles at a node exactly at the
    // isovalue): the enclosed volume changes by the tetrahedron (o, a, b, c).
    const double tet = std::abs((P(a) - P(o)).dot((P(b) - P(o)).cross(P(c) - P(o)))) / 6.0;
    if (point_triangle_distance(P(o), P(a), P(b), P(c)) > max_collapse_ && tet > kMinAreaFraction * h_ * h_ * h_) return false;
    for (const uint32_t t : std::vector<uint32_t>(vt_[o])) {
      alive_[t] = 0;
      for (int k = 0; k < 3; ++k) unlink(t, corner(t, k));
    }
    add_triangle(a, b, c);
    return true;
  }

  static double point_triangle_distance(const Vec& p, const Vec& a, const Vec& b, const Vec& c) {
    const auto segment = [&](const Vec& s, const Vec& e) {
      const double l2 = (e - s).squaredNorm();
      const double t = l2 > 0.0 ? std::clamp((p - s).dot(e - s) / l2, 0.0, 1.0) : 0.0;
      return (s + t * (e - s) - p).norm();
    };
    double d = std::min({segment(a, b), segment(b, c), segment(c, a)});
    const Vec n = (b - a).cross(c - a);
    if (n.squaredNorm() > 0.0) {
      const Vec q = p - (p - a).dot(n) / n.squaredNorm() * n;  // projection on the plane
      const bool inside = (b - a).cross(q - a).dot(n) >= 0.0 && (c - b).cross(q - b).dot(n) >= 0.0 &&
                          (a - c).cross(q - c).dot(n) >= 0.0;
      if (inside) d = std::min(d, (p - q).norm());
    }
    return d;
  }

  void add_triangle(uint32_t a, uint32_t b, uint32_t c) {
    const auto t = static_cast<uint32_t>(alive_.size());
    tri_.insert(tri_.end(), {a, b, c});
    alive_.push_back(1);
    for (const uint32_t v : {a, b, c}) vt_[v].push_back(t);
  }

  // Collapses edge (u, v) into v (u disappears); false, changing nothing, when refused. When the link
  // condition is what refuses it, `extra` gets the common neighbours that are not far corners.
  bool collapse(uint32_t u, uint32_t v, std::vector<uint32_t>* extra = nullptr, uint32_t* tent = nullptr) {
    if ((P(u) - P(v)).norm() > max_collapse_) return false;
    const std::vector<uint32_t> T = edge_triangles(u, v);
    if (T.empty() || T.size() > 2) return false;
    std::vector<uint32_t> opp;
    for (const uint32_t t : T) opp.push_back(third(t, u, v));
    std::sort(opp.begin(), opp.end());
    if (opp.size() == 2 && opp[0] == opp[1]) return false;
    if (std::find(opp.begin(), opp.end(), u) != opp.end() || std::find(opp.begin(), opp.end(), v) != opp.end()) return false;
    const bool border_edge = T.size() == 1;
    // Every vertex keeps at least 3 neighbours on a closed surface (2 on a border): no fold. (Reported
    // with the link condition's obstacles, so that the caller can remove either.)
    bool refused = false;
    for (const uint32_t o : opp)
      if (neighbours(o).size() <= (border_edge ? 2u : 3u)) {
        if (tent) *tent = o;
        refused = true;
      }
    // Link condition.
    const std::vector<uint32_t> nu = neighbours(u), nv = neighbours(v);
    std::vector<uint32_t> common;
    std::set_intersection(nu.begin(), nu.end(), nv.begin(), nv.end(), std::back_inserter(common));
    if (common != opp) {
      if (extra) std::set_difference(common.begin(), common.end(), opp.begin(), opp.end(), std::back_inserter(*extra));
      return false;
    }
    if (refused) return false;
    if (!border_edge && on_border(u)) return false;
    if (nu.size() + nv.size() - common.size() - 2 < (border_edge ? 2u : 3u)) return false;
    // No surviving triangle around u turns over: each ends on the outer side of u's ring (the sum of
    // the fan's area vectors, the area vector of the ring polygon), and one that was on that side
    // also keeps a positive dot product with its old normal. A triangle already folded (or too small
    // to have a direction) may unfold.
    if (P(u) != P(v)) {
      Vec ring = Vec::Zero();
      for (const uint32_t t : vt_[u]) ring += normal(t);
      if (!(ring.norm() > tiny2_)) return false;
      for (const uint32_t t : vt_[u]) {
        if (std::find(T.begin(), T.end(), t) != T.end()) continue;
        uint32_t id[3] = {corner(t, 0), corner(t, 1), corner(t, 2)};
        for (auto& i : id)
          if (i == u) i = v;
        const Vec before = normal(t), after = normal(id[0], id[1], id[2]);
        if (before.norm() > tiny2_ ? !(after.dot(before) > 0.0) : !(after.dot(ring) > 0.0)) return false;
      }
    }
    for (const uint32_t t : T) {
      alive_[t] = 0;
      for (int c = 0; c < 3; ++c) unlink(t, corner(t, c));
    }
    for (const uint32_t t : vt_[u]) {
      for (int c = 0; c < 3; ++c)
        if (corner(t, c) == u) tri_[3 * std::size_t{t} + static_cast<std::size_t>(c)] = v;
      vt_[v].push_back(t);
    }
    longest_collapse = std::max(longest_collapse, (P(u) - P(v)).norm());
    vt_[u].clear();
    std::sort(vt_[v].begin(), vt_[v].end());
    return true;
  }

  // Flips edge `edge` (corners edge, edge + 1) of triangle t; false, changing nothing, when refused.
  bool flip(uint32_t t, int edge) {
    const uint32_t a = corner(t, edge), b = corner(t, (edge + 1) % 3), c = corner(t, (edge + 2) % 3);
    if (a == b || b == c || a == c) return false;
    const std::vector<uint32_t> T = edge_triangles(a, b);
    if (T.size() != 2) return false;
    const uint32_t s = T[0] == t ? T[1] : T[0];
    // s must hold the edge as b -> a (consistent orientation).
    int sa = -1;
    for (int k = 0; k < 3; ++k)
      if (corner(s, k) == b && corner(s, (k + 1) % 3) == a) sa = k;
    if (sa < 0) return false;
    const uint32_t d = corner(s, (sa + 2) % 3);
    if (d == c || d == a || d == b || !edge_triangles(c, d).empty()) return false;
    if (neighbours(a).size() <= 3 || neighbours(b).size() <= 3) return false;
    const Vec ref = normal(t) + normal(s);
    const Vec n1 = normal(c, a, d), n2 = normal(d, b, c);
    if (!(ref.norm() > tiny2_ && n1.dot(ref) > 0.0 && n2.dot(ref) > 0.0)) return false;
    const Vec old1[3] = {P(a), P(b), P(c)}, old2[3] = {P(b), P(a), P(d)};
    const Vec new1[3] = {P(c), P(a), P(d)}, new2[3] = {P(d), P(b), P(c)};
    if (!(std::min(min_angle_deg(new1), min_angle_deg(new2)) > std::min(min_angle_deg(old1), min_angle_deg(old2)) + 1e-9)) {
      return false;
    }
    const auto set = [&](uint32_t tt, uint32_t p, uint32_t q, uint32_t r) {
      tri_[3 * std::size_t{tt}] = p;
      tri_[3 * std::size_t{tt} + 1] = q;
      tri_[3 * std::size_t{tt} + 2] = r;
    };
    set(t, c, a, d);
    set(s, d, b, c);
    unlink(t, b);
    unlink(s, a);
    vt_[d].push_back(t);
    vt_[c].push_back(s);
    std::sort(vt_[d].begin(), vt_[d].end());
    std::sort(vt_[c].begin(), vt_[c].end());
    return true;
  }
};

}  // namespace

const char* degeneracy_name(Degeneracy d) {
  switch (d) {
    case Degeneracy::kNone: return "none";
    case Degeneracy::kRepeatedIndex: return "repeated index";
    case Degeneracy::kCoincidentCorners: return "coincident corners";
    case Degeneracy::kTinyArea: return "tiny area";
    case Degeneracy::kSliver: return "sliver";
  }
  return "?";
}

Degeneracy triangle_degeneracy(const SurfaceMesh& mesh, int64_t t, double cell_mm) {
  const auto f = static_cast<std::size_t>(3 * t);
  const uint32_t id[3] = {mesh.triangles[f], mesh.triangles[f + 1], mesh.triangles[f + 2]};
  Vec p[3];
  for (int c = 0; c < 3; ++c)
    for (int a = 0; a < 3; ++a) p[c][a] = mesh.vertices[3 * std::size_t{id[c]} + static_cast<std::size_t>(a)];
  return classify(id, p, cell_mm);
}

std::string DegenerateTriangleCount::summary() const {
  return std::to_string(total()) + " (" + std::to_string(repeated_index) + " repeated index, " +
         std::to_string(coincident_corners) + " coincident corners, " + std::to_string(tiny_area) + " tiny area, " +
         std::to_string(sliver) + " sliver)";
}

DegenerateTriangleCount count_degenerate_triangles(const SurfaceMesh& mesh, double cell_mm) {
  check_cell(cell_mm);
  const int64_t nf = mesh.triangle_count();
  int64_t r = 0, c = 0, a = 0, s = 0;
#pragma omp parallel for schedule(static) reduction(+ : r, c, a, s)
  for (int64_t t = 0; t < nf; ++t) {
    switch (triangle_degeneracy(mesh, t, cell_mm)) {
      case Degeneracy::kRepeatedIndex: ++r; break;
      case Degeneracy::kCoincidentCorners: ++c; break;
      case Degeneracy::kTinyArea: ++a; break;
      case Degeneracy::kSliver: ++s; break;
      case Degeneracy::kNone: break;
    }
  }
  return {r, c, a, s};
}

double lattice_cell_mm(const SurfaceMesh& mesh) { return mesh.lattice.spacing.minCoeff(); }

DegenerateRemovalStats remove_degenerate_triangles(SurfaceMesh& mesh, double cell_mm, bool may_move_vertices) {
  check_cell(cell_mm);
  DegenerateRemovalStats stats;
  stats.before = count_degenerate_triangles(mesh, cell_mm);
  Repairer r(mesh, cell_mm);
  stats.merged = r.merge();
  r.repair(stats.collapsed, stats.flipped);
  if (may_move_vertices && r.relax() > 0) r.repair(stats.collapsed, stats.flipped);
  stats.relaxed = r.relaxed;
  stats.dropped_components = r.drop_degenerate_components();
  stats.handles_cut = r.handles_cut;
  stats.tents_removed = r.tents_removed;
  stats.longest_collapse_mm = r.longest_collapse;
  r.write(mesh);
  stats.after = count_degenerate_triangles(mesh, cell_mm);
  return stats;
}

}  // namespace ctsurg
