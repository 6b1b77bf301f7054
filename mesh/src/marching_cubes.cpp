#include "ctsurg/mesh/marching_cubes.h"

#include "ctsurg/core/error.h"

#include <Eigen/Dense>
#include <omp.h>

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

namespace ctsurg {

namespace {

// Cell corner c sits at offset (c & 1, c >> 1 & 1, c >> 2 & 1) from the cell's lower node.
// Cell edge e = 4 * a + u + 2 * v runs along axis a from the corner whose bits on the two other
// axes b < c are u and v.
constexpr std::array<std::array<int, 2>, 3> kOtherAxes{{{1, 2}, {0, 2}, {0, 1}}};

int edge_base_corner(int e) {
  const int a = e / 4, u = e % 2, v = (e / 2) % 2;
  return (u << kOtherAxes[static_cast<std::size_t>(a)][0]) | (v << kOtherAxes[static_cast<std::size_t>(a)][1]);
}

int edge_between(int c0, int c1) {
  const int d = c0 ^ c1;
  const int a = d == 1 ? 0 : d == 2 ? 1 : 2;
  const int base = c0 & ~d;
  const auto& o = kOtherAxes[static_cast<std::size_t>(a)];
  return 4 * a + ((base >> o[0]) & 1) + 2 * ((base >> o[1]) & 1);
}

Eigen::Vector3d edge_midpoint(int e) {
  const int a = e / 4, base = edge_base_corner(e);
  Eigen::Vector3d p(base & 1, (base >> 1) & 1, (base >> 2) & 1);
  p[a] = 0.5;
  return p;
}

// True when cell edges e0 and e1 (distinct) lie on a common cell face.
bool share_face(int e0, int e1) {
  const auto faces = [](int e) {
    const int a = e / 4, base = edge_base_corner(e);
    std::array<int, 2> f{};
    for (int n = 0; n < 2; ++n) {
      const int b = kOtherAxes[static_cast<std::size_t>(a)][static_cast<std::size_t>(n)];
      f[static_cast<std::size_t>(n)] = 2 * b + ((base >> b) & 1);  // face: axis b, side
    }
    return f;
  };
  const auto f0 = faces(e0), f1 = faces(e1);
  for (int x : f0)
    for (int y : f1)
      if (x == y) return true;
  return false;
}

constexpr int kMaxTriangles = 12;

struct CaseTable {
  std::array<uint8_t, 256> triangle_count{};
  std::array<std::array<std::array<int8_t, 3>, kMaxTriangles>, 256> triangles{};
};

// Minimum-weight triangulation of one loop of cell edges (see marching_cubes.h, step 3).
void triangulate_loop(const std::vector<int>& loop, std::vector<std::array<int8_t, 3>>& out) {
  const int n = static_cast<int>(loop.size());
  std::vector<Eigen::Vector3d> p;
  for (int e : loop) p.push_back(edge_midpoint(e));
  const auto is_loop_edge = [n](int i, int j) { return j - i == 1 || (i == 0 && j == n - 1); };
  const auto side_weight = [&](int i, int j) {
    return !is_loop_edge(i, j) && share_face(loop[static_cast<std::size_t>(i)], loop[static_cast<std::size_t>(j)])
               ? 1e6
               : 0.0;
  };
  const auto weight = [&](int i, int m, int j) {
    const Eigen::Vector3d a = p[static_cast<std::size_t>(i)], b = p[static_cast<std::size_t>(m)],
                          c = p[static_cast<std::size_t>(j)];
    const double area = 0.5 * (b - a).cross(c - a).norm();
    const double perimeter = (b - a).norm() + (c - b).norm() + (a - c).norm();
    return perimeter * perimeter / std::max(area, 1e-12) + side_weight(i, m) + side_weight(m, j) + side_weight(i, j);
  };
  std::vector<double> cost(static_cast<std::size_t>(n * n), 0.0);
  std::vector<int> split(static_cast<std::size_t>(n * n), -1);
  const auto at = [n](int i, int j) { return static_cast<std::size_t>(i * n + j); };
  for (int len = 2; len < n; ++len) {
    for (int i = 0; i + len < n; ++i) {
      const int j = i + len;
      double best = std::numeric_limits<double>::infinity();
      for (int m = i + 1; m < j; ++m) {
        const double c = cost[at(i, m)] + cost[at(m, j)] + weight(i, m, j);
        if (c < best) {
          best = c;
          split[at(i, j)] = m;
        }
      }
      cost[at(i, j)] = best;
    }
  }
  // Triangles (i, m, j) with i < m < j keep the loop's orientation.
  std::vector<std::pair<int, int>> stack{{0, n - 1}};
  while (!stack.empty()) {
    const auto [i, j] = stack.back();
    stack.pop_back();
    if (j - i < 2) continue;
    const int m = split[at(i, j)];
    out.push_back({static_cast<int8_t>(loop[static_cast<std::size_t>(i)]), static_cast<int8_t>(loop[static_cast<std::size_t>(m)]),
                   static_cast<int8_t>(loop[static_cast<std::size_t>(j)])});
    stack.push_back({m, j});
    stack.push_back({i, m});
  }
}

CaseTable build_case_table() {
  CaseTable table;
  // Faces (axis a, side s), corners counter-clockwise seen from outside: with (a, b, c) a cyclic
  // permutation of (x, y, z), (u, v) along (b, c) runs (0,0) (1,0) (1,1) (0,1) on the + side and
  // the reverse on the - side.
  std::array<std::array<int, 4>, 6> faces{};
  for (int a = 0; a < 3; ++a) {
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    for (int s = 0; s < 2; ++s) {
      static constexpr int kPlus[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
      static constexpr int kMinus[4][2] = {{0, 0}, {0, 1}, {1, 1}, {1, 0}};
      for (int n = 0; n < 4; ++n) {
        const int* uv = s ? kPlus[n] : kMinus[n];
        faces[static_cast<std::size_t>(2 * a + s)][static_cast<std::size_t>(n)] = (s << a) | (uv[0] << b) | (uv[1] << c);
      }
    }
  }
  for (int config = 0; config < 256; ++config) {
    const auto inside = [config](int corner) { return ((config >> corner) & 1) != 0; };
    std::array<int, 12> next;
    next.fill(-1);
    for (const auto& q : faces) {
      for (int p = 0; p < 4; ++p) {
        if (inside(q[static_cast<std::size_t>(p)]) || !inside(q[static_cast<std::size_t>((p + 1) % 4)])) continue;
        // Entering a run of inside corners between q[p] and q[p+1]; find where it is left.
        int r = p + 1;
        while (inside(q[static_cast<std::size_t>((r + 1) % 4)])) ++r;
        const int enter = edge_between(q[static_cast<std::size_t>(p)], q[static_cast<std::size_t>((p + 1) % 4)]);
        const int leave = edge_between(q[static_cast<std::size_t>(r % 4)], q[static_cast<std::size_t>((r + 1) % 4)]);
        assert(next[static_cast<std::size_t>(enter)] == -1);
        next[static_cast<std::size_t>(enter)] = leave;
      }
    }
    std::vector<std::array<int8_t, 3>> tris;
    std::array<bool, 12> used{};
    for (int start = 0; start < 12; ++start) {
      if (next[static_cast<std::size_t>(start)] < 0 || used[static_cast<std::size_t>(start)]) continue;
      std::vector<int> loop;
      for (int e = start; !used[static_cast<std::size_t>(e)]; e = next[static_cast<std::size_t>(e)]) {
        used[static_cast<std::size_t>(e)] = true;
        loop.push_back(e);
      }
      triangulate_loop(loop, tris);
    }
    assert(tris.size() <= kMaxTriangles);
    table.triangle_count[static_cast<std::size_t>(config)] = static_cast<uint8_t>(tris.size());
    std::copy(tris.begin(), tris.end(), table.triangles[static_cast<std::size_t>(config)].begin());
  }
  return table;
}

const CaseTable& case_table() {
  static const CaseTable table = build_case_table();
  return table;
}

constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();

// Vertex ids of the crossed lattice edges whose lower node lies in one z-slice of nodes, per node
// and axis.
struct SliceIds {
  int64_t slice = -1;
  std::array<std::vector<uint32_t>, 3> id;
};

struct Lattice {
  const float* f;
  int64_t nx, ny, nz;
  double iso;
  float value(int64_t i, int64_t j, int64_t k) const { return f[i + nx * (j + ny * k)]; }
  bool inside(int64_t i, int64_t j, int64_t k) const { return double(value(i, j, k)) >= iso; }
  // Whether the edge from node (i, j, k) along axis a exists and crosses iso.
  bool crossed(int64_t i, int64_t j, int64_t k, int a) const {
    const bool in = inside(i, j, k);
    if (a == 0) return i + 1 < nx && inside(i + 1, j, k) != in;
    if (a == 1) return j + 1 < ny && inside(i, j + 1, k) != in;
    return k + 1 < nz && inside(i, j, k + 1) != in;
  }
  int cell_case(int64_t i, int64_t j, int64_t k) const {
    int c = 0;
    for (int n = 0; n < 8; ++n) c |= int(inside(i + (n & 1), j + ((n >> 1) & 1), k + ((n >> 2) & 1))) << n;
    return c;
  }
  // Central-difference gradient in index space (one-sided on the border).
  Eigen::Vector3d gradient(int64_t i, int64_t j, int64_t k) const {
    const std::array<int64_t, 3> p{i, j, k}, n{nx, ny, nz};
    Eigen::Vector3d g;
    for (int a = 0; a < 3; ++a) {
      std::array<int64_t, 3> lo = p, hi = p;
      lo[static_cast<std::size_t>(a)] = std::max<int64_t>(p[static_cast<std::size_t>(a)] - 1, 0);
      hi[static_cast<std::size_t>(a)] = std::min<int64_t>(p[static_cast<std::size_t>(a)] + 1, n[static_cast<std::size_t>(a)] - 1);
      const double h = double(hi[static_cast<std::size_t>(a)] - lo[static_cast<std::size_t>(a)]);
      g[a] = (double(value(hi[0], hi[1], hi[2])) - double(value(lo[0], lo[1], lo[2]))) / h;
    }
    return g;
  }
};

void fill_slice_ids(const Lattice& L, int64_t k, uint32_t first, SliceIds& s) {
  s.slice = k;
  const auto n = static_cast<std::size_t>(L.nx * L.ny);
  for (auto& v : s.id) v.assign(n, kNone);
  uint32_t next = first;
  for (int64_t j = 0; j < L.ny; ++j)
    for (int64_t i = 0; i < L.nx; ++i)
      for (int a = 0; a < 3; ++a)
        if (L.crossed(i, j, k, a)) s.id[static_cast<std::size_t>(a)][static_cast<std::size_t>(i + L.nx * j)] = next++;
}

}  // namespace

SurfaceMesh marching_cubes(const Volume<float>& field, double iso, const MarchingCubesOptions& options) {
  const ImageGeometry& g = field.geometry;
  if (!std::isfinite(iso)) throw InputError("field", "iso", "the isovalue must be finite");
  if (g.dims[0] < 2 || g.dims[1] < 2 || g.dims[2] < 2) {
    throw InputError("field", "dims", "marching cubes needs at least 2 nodes along every axis");
  }
  if (field.voxels.size() != static_cast<std::size_t>(g.voxel_count())) {
    throw InputError("field", "voxels", "voxel count does not match the geometry");
  }
  const CaseTable& table = case_table();
  const Lattice L{field.voxels.data(), g.dims[0], g.dims[1], g.dims[2], iso};
  const int threads = options.threads > 0 ? options.threads : omp_get_max_threads();

  // Pass 1: per slice k, crossed edges with lower node in slice k and triangles of cells in slab k.
  const int64_t nz = L.nz;
  std::vector<int64_t> vcount(static_cast<std::size_t>(nz + 1), 0), tcount(static_cast<std::size_t>(nz + 1), 0);
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int64_t k = 0; k < nz; ++k) {
    int64_t nv = 0, nt = 0;
    for (int64_t j = 0; j < L.ny; ++j)
      for (int64_t i = 0; i < L.nx; ++i) {
        for (int a = 0; a < 3; ++a) nv += L.crossed(i, j, k, a);
        if (k + 1 < nz && j + 1 < L.ny && i + 1 < L.nx) nt += table.triangle_count[static_cast<std::size_t>(L.cell_case(i, j, k))];
      }
    vcount[static_cast<std::size_t>(k)] = nv;
    tcount[static_cast<std::size_t>(k)] = nt;
  }
  // Exclusive prefix sums: first vertex and triangle of every slice.
  std::vector<int64_t> vfirst(static_cast<std::size_t>(nz + 1), 0), tfirst(static_cast<std::size_t>(nz + 1), 0);
  for (int64_t k = 0; k < nz; ++k) {
    vfirst[static_cast<std::size_t>(k + 1)] = vfirst[static_cast<std::size_t>(k)] + vcount[static_cast<std::size_t>(k)];
    tfirst[static_cast<std::size_t>(k + 1)] = tfirst[static_cast<std::size_t>(k)] + tcount[static_cast<std::size_t>(k)];
  }
  const int64_t V = vfirst[static_cast<std::size_t>(nz)], F = tfirst[static_cast<std::size_t>(nz)];
  if (V >= int64_t(kNone)) throw RuntimeError("marching cubes: more than 2^32 - 1 vertices");

  SurfaceMesh mesh;
  mesh.lattice = g;
  mesh.iso = iso;
  mesh.vertices.resize(static_cast<std::size_t>(3 * V));
  mesh.normals.resize(static_cast<std::size_t>(3 * V));
  mesh.grid_cell.resize(static_cast<std::size_t>(3 * V));
  mesh.grid_weights.resize(static_cast<std::size_t>(8 * V));
  mesh.nearest_node.resize(static_cast<std::size_t>(3 * V));
  mesh.triangles.resize(static_cast<std::size_t>(3 * F));
  if (V == 0) return mesh;

  const Eigen::Matrix3d M = g.index_to_world_matrix();
  const Eigen::Matrix3d gradient_to_world = M.inverse().transpose();  // grad_world = M^-T grad_index
  const Eigen::Vector3d origin = g.origin;
  // The table orients triangles in index space; a lattice whose index-to-world map reverses
  // orientation (det < 0, e.g. a flipped slice axis) needs the opposite winding in LPS.
  const bool flip = M.determinant() < 0.0;

  // Pass 2: each slice writes its own vertices and its slab's triangles at its offsets.
#pragma omp parallel num_threads(threads)
  {
    SliceIds cur, nxt;
#pragma omp for schedule(static)
    for (int64_t k = 0; k < nz; ++k) {
      if (nxt.slice == k) {
        std::swap(cur, nxt);
      } else {
        fill_slice_ids(L, k, static_cast<uint32_t>(vfirst[static_cast<std::size_t>(k)]), cur);
      }
      if (k + 1 < nz) fill_slice_ids(L, k + 1, static_cast<uint32_t>(vfirst[static_cast<std::size_t>(k + 1)]), nxt);

      // Vertices of slice k.
      for (int64_t j = 0; j < L.ny; ++j)
        for (int64_t i = 0; i < L.nx; ++i)
          for (int a = 0; a < 3; ++a) {
            const uint32_t id = cur.id[static_cast<std::size_t>(a)][static_cast<std::size_t>(i + L.nx * j)];
            if (id == kNone) continue;
            const std::array<int64_t, 3> p{i, j, k};
            std::array<int64_t, 3> q = p;
            ++q[static_cast<std::size_t>(a)];
            const double vp = L.value(p[0], p[1], p[2]), vq = L.value(q[0], q[1], q[2]);
            const double t = std::clamp((iso - vp) / (vq - vp), 0.0, 1.0);
            Eigen::Vector3d ijk{double(i), double(j), double(k)};
            ijk[a] += t;
            const Eigen::Vector3d x = origin + M * ijk;
            const Eigen::Vector3d grad =
                gradient_to_world * ((1.0 - t) * L.gradient(p[0], p[1], p[2]) + t * L.gradient(q[0], q[1], q[2]));
            const bool p_inside = vp >= iso;
            Eigen::Vector3d n = -grad;
            if (!(n.norm() > 1e-30) || !n.allFinite()) n = (p_inside ? 1.0 : -1.0) * M.col(a);
            n.normalize();
            const std::size_t v = id;
            std::array<int64_t, 3> cell{};
            Eigen::Vector3d frac;
            const std::array<int64_t, 3> dims{L.nx, L.ny, L.nz};
            for (int b = 0; b < 3; ++b) {
              cell[static_cast<std::size_t>(b)] = std::min(p[static_cast<std::size_t>(b)], dims[static_cast<std::size_t>(b)] - 2);
              frac[b] = ijk[b] - double(cell[static_cast<std::size_t>(b)]);
            }
            for (int b = 0; b < 3; ++b) {
              mesh.vertices[3 * v + static_cast<std::size_t>(b)] = static_cast<float>(x[b]);
              mesh.normals[3 * v + static_cast<std::size_t>(b)] = static_cast<float>(n[b]);
              mesh.grid_cell[3 * v + static_cast<std::size_t>(b)] = static_cast<int32_t>(cell[static_cast<std::size_t>(b)]);
              mesh.nearest_node[3 * v + static_cast<std::size_t>(b)] =
                  static_cast<int32_t>(p_inside ? p[static_cast<std::size_t>(b)] : q[static_cast<std::size_t>(b)]);
            }
            for (int c = 0; c < 8; ++c) {
              double w = 1.0;
              for (int b = 0; b < 3; ++b) w *= ((c >> b) & 1) ? frac[b] : 1.0 - frac[b];
              mesh.grid_weights[8 * v + static_cast<std::size_t>(c)] = static_cast<float>(w);
            }
          }

      // Triangles of the cells between slices k and k + 1.
      if (k + 1 == nz) continue;
      std::size_t out = static_cast<std::size_t>(3 * tfirst[static_cast<std::size_t>(k)]);
      for (int64_t j = 0; j + 1 < L.ny; ++j)
        for (int64_t i = 0; i + 1 < L.nx; ++i) {
          const auto config = static_cast<std::size_t>(L.cell_case(i, j, k));
          const int nt = table.triangle_count[config];
          for (int t = 0; t < nt; ++t, out += 3)
            for (int c = 0; c < 3; ++c) {
              const int e = table.triangles[config][static_cast<std::size_t>(t)][static_cast<std::size_t>(c)];
              const int base = edge_base_corner(e);
              const SliceIds& s = (base >> 2) & 1 ? nxt : cur;
              const int64_t node = (i + (base & 1)) + L.nx * (j + ((base >> 1) & 1));
              const uint32_t id = s.id[static_cast<std::size_t>(e / 4)][static_cast<std::size_t>(node)];
              assert(id != kNone);
              mesh.triangles[out + static_cast<std::size_t>(flip && c > 0 ? 3 - c : c)] = id;
            }
        }
    }
  }
  return mesh;
}

bool inside_touches_border(const Volume<float>& field, double iso) {
  const auto& d = field.geometry.dims;
  for (int64_t k = 0; k < d[2]; ++k)
    for (int64_t j = 0; j < d[1]; ++j) {
      const bool face_row = k == 0 || k == d[2] - 1 || j == 0 || j == d[1] - 1;
      for (int64_t i = 0; i < d[0]; i += (face_row ? 1 : std::max<int64_t>(d[0] - 1, 1)))
        if (double(field(i, j, k)) >= iso) return true;
    }
  return false;
}

}  // namespace ctsurg
