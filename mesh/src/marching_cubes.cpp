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
#include <memory>
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

// Number of set bits of a 3-bit edge-flag byte, and of its bits below axis a.
constexpr std::array<uint8_t, 8> kPop3{0, 1, 1, 2, 1, 2, 2, 3};

// Central-difference gradient of f in index space at node (i, j, k) (one-sided on the border).
Eigen::Vector3d node_gradient(const float* f, int64_t i, int64_t j, int64_t k, const std::array<int64_t, 3>& n) {
  const int64_t sx = 1, sy = n[0], sz = n[0] * n[1];
  const int64_t p = i + sy * j + sz * k;
  if (i > 0 && j > 0 && k > 0 && i + 1 < n[0] && j + 1 < n[1] && k + 1 < n[2]) {
    return {0.5 * (double(f[p + sx]) - double(f[p - sx])), 0.5 * (double(f[p + sy]) - double(f[p - sy])),
            0.5 * (double(f[p + sz]) - double(f[p - sz]))};
  }
  const auto diff = [&](int64_t c, int64_t m, int64_t stride) {
    const int64_t lo = c > 0 ? 1 : 0, hi = c + 1 < m ? 1 : 0;
    return (double(f[p + hi * stride]) - double(f[p - lo * stride])) / double(lo + hi);
  };
  return {diff(i, n[0], sx), diff(j, n[1], sy), diff(k, n[2], sz)};
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
  const int threads = options.threads > 0 ? options.threads : omp_get_max_threads();
  const int64_t nx = g.dims[0], ny = g.dims[1], nz = g.dims[2], sxy = nx * ny;
  const auto N = static_cast<std::size_t>(g.voxel_count());
  const float* f = field.voxels.data();

  // Per node, 1 byte each: its side of iso; the crossing flags of the 3 lattice edges leaving it
  // (bit a: the edge along axis a exists and crosses); the case of the cell it is the lower corner
  // of (corner c at (c & 1, c >> 1 & 1, c >> 2 & 1); unused on the last row, column and slice).
  // Left uninitialised (every byte read is written first): zero-filling them would cost as much as
  // pass 0.
  const std::unique_ptr<uint8_t[]> inside(new uint8_t[N]), edges(new uint8_t[N]), cases(new uint8_t[N]);
  // Per node row (j, k): its vertex count (a row's vertex ids are consecutive, in (i, axis) order)
  // and the first and last node with a crossed edge (the trimming of flying edges: the passes skip
  // the empty ends of rows; lo > hi for a row with none).
  const auto rows = static_cast<std::size_t>(ny * nz);
  std::vector<uint32_t> row_vertices(rows);
  std::vector<int32_t> row_lo(rows), row_hi(rows);
  // Per node row: 0 when every node is outside, 1 when every node is inside, 2 when mixed. Rows of
  // empty space (or solid tissue) with uniform neighbours skip the byte loops of pass 1.
  std::vector<uint8_t> row_side(rows);

  // Pass 0. For a float f, f >= iso (in double) exactly when f >= iso_f, the least float >= iso,
  // so the comparison runs on floats (twice the SIMD width of doubles).
  float iso_f = static_cast<float>(iso);
  if (double(iso_f) < iso) iso_f = std::nextafter(iso_f, std::numeric_limits<float>::infinity());
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int64_t k = 0; k < nz; ++k)
    for (int64_t j = 0; j < ny; ++j) {
      uint8_t* __restrict in = inside.get() + nx * j + sxy * k;
      const float* __restrict fr = f + nx * j + sxy * k;
      uint8_t any = 0, all = 1;
      for (int64_t i = 0; i < nx; ++i) {
        in[i] = fr[i] >= iso_f;
        any |= in[i];
        all &= in[i];
      }
      row_side[static_cast<std::size_t>(j + ny * k)] = static_cast<uint8_t>(all ? 1 : any ? 2 : 0);
    }

  // Pass 1 (parallel over slices): edge flags, per-row vertex counts, cell cases and the number of
  // vertices (edges leaving slice k) and triangles (cells between k and k + 1) of every slice. The
  // loops are plain byte loops over a row so that they vectorise.
  std::vector<int64_t> vcount(static_cast<std::size_t>(nz), 0), tcount(static_cast<std::size_t>(nz), 0);
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int64_t k = 0; k < nz; ++k) {
    int64_t nv = 0, nt = 0;
    for (int64_t j = 0; j < ny; ++j) {
      const int64_t r = nx * j + sxy * k;
      const uint8_t* __restrict a = inside.get() + r;
      uint8_t* __restrict e = edges.get() + r;
      // A uniform row whose neighbours along +y and +z (where they exist) are uniform on the same
      // side has no crossed edge and, with the neighbour along +y+z too, only cells of one case.
      const auto side = [&](int64_t jj, int64_t kk) { return row_side[static_cast<std::size_t>(jj + ny * kk)]; };
      const uint8_t s0 = side(j, k);
      const bool same_y = j + 1 == ny || side(j + 1, k) == s0, same_z = k + 1 == nz || side(j, k + 1) == s0;
      if (s0 != 2 && same_y && same_z) {
        std::memset(e, 0, static_cast<std::size_t>(nx));
        row_vertices[static_cast<std::size_t>(j + ny * k)] = 0;
        row_lo[static_cast<std::size_t>(j + ny * k)] = static_cast<int32_t>(nx);
        row_hi[static_cast<std::size_t>(j + ny * k)] = -1;
        if (k + 1 == nz || j + 1 == ny) continue;
        if (side(j + 1, k + 1) == s0) {
          std::memset(cases.get() + r, s0 ? 0xff : 0, static_cast<std::size_t>(nx));
          continue;
        }
      }
      for (int64_t i = 0; i + 1 < nx; ++i) e[i] = static_cast<uint8_t>(a[i] ^ a[i + 1]);
      e[nx - 1] = 0;
      if (j + 1 < ny)
        for (int64_t i = 0; i < nx; ++i) e[i] = static_cast<uint8_t>(e[i] | (a[i] ^ a[i + nx]) << 1);
      if (k + 1 < nz)
        for (int64_t i = 0; i < nx; ++i) e[i] = static_cast<uint8_t>(e[i] | (a[i] ^ a[i + sxy]) << 2);
      uint32_t rv = 0;
      int64_t lo = nx, hi = -1;
      for (int64_t i = 0; i < nx; ++i) rv += kPop3[e[i]];
      if (rv > 0) {
        for (lo = 0; e[lo] == 0;) ++lo;
        for (hi = nx - 1; e[hi] == 0;) --hi;
      }
      row_vertices[static_cast<std::size_t>(j + ny * k)] = rv;
      row_lo[static_cast<std::size_t>(j + ny * k)] = static_cast<int32_t>(lo);
      row_hi[static_cast<std::size_t>(j + ny * k)] = static_cast<int32_t>(hi);
      nv += rv;
      if (k + 1 == nz || j + 1 == ny) continue;
      const uint8_t* __restrict a1 = a + nx;
      const uint8_t* __restrict b0 = a + sxy;
      const uint8_t* __restrict b1 = b0 + nx;
      uint8_t* __restrict c = cases.get() + r;
      for (int64_t i = 0; i + 1 < nx; ++i)
        c[i] = static_cast<uint8_t>(a[i] | a[i + 1] << 1 | a1[i] << 2 | a1[i + 1] << 3 | b0[i] << 4 | b0[i + 1] << 5 |
                                    b1[i] << 6 | b1[i + 1] << 7);
      for (int64_t i = 0; i + 1 < nx; ++i) nt += table.triangle_count[c[i]];
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
  if (V >= int64_t(std::numeric_limits<uint32_t>::max())) throw RuntimeError("marching cubes: more than 2^32 - 1 vertices");

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
  const std::array<int64_t, 3> dims{nx, ny, nz};
  // The table orients triangles in index space; a lattice whose index-to-world map reverses
  // orientation (det < 0, e.g. a flipped slice axis) needs the opposite winding in LPS.
  const bool flip = M.determinant() < 0.0;
  // Cell edge e leaves the cell corner edge_base_corner(e) along axis e / 4: that corner's node row
  // is one of the 4 rows (j, k), (j + 1, k), (j, k + 1), (j + 1, k + 1) (index by + 2 bz) and its
  // node is i or i + 1 (bx).
  std::array<uint8_t, 12> edge_row{}, edge_dx{}, edge_axis{};
  for (int e = 0; e < 12; ++e) {
    const int base = edge_base_corner(e);
    edge_row[static_cast<std::size_t>(e)] = static_cast<uint8_t>(((base >> 1) & 1) + 2 * ((base >> 2) & 1));
    edge_dx[static_cast<std::size_t>(e)] = static_cast<uint8_t>(base & 1);
    edge_axis[static_cast<std::size_t>(e)] = static_cast<uint8_t>(e / 4);
  }

  // Pass 2 (parallel over slices): each slice writes its own vertices and the triangles of the
  // cells above it at its offsets.
#pragma omp parallel num_threads(threads)
  {
    std::vector<uint32_t> row_first(static_cast<std::size_t>(2 * ny));  // first vertex id of rows of slices k, k + 1
#pragma omp for schedule(static)
    for (int64_t k = 0; k < nz; ++k) {
      for (int64_t s = 0; s < 2 && k + s < nz; ++s) {
        auto next = static_cast<uint32_t>(vfirst[static_cast<std::size_t>(k + s)]);
        for (int64_t j = 0; j < ny; ++j) {
          row_first[static_cast<std::size_t>(j + ny * s)] = next;
          next += row_vertices[static_cast<std::size_t>(j + ny * (k + s))];
        }
      }

      // Vertices of slice k.
      for (int64_t j = 0; j < ny; ++j) {
        std::size_t v = row_first[static_cast<std::size_t>(j)];
        const uint8_t* e = edges.get() + nx * j + sxy * k;
        const auto row = static_cast<std::size_t>(j + ny * k);
        for (int64_t i = row_lo[row]; i <= row_hi[row]; ++i) {
          if (e[i] == 0) continue;
          for (int a = 0; a < 3; ++a) {
            if (!((e[i] >> a) & 1)) continue;
            const std::array<int64_t, 3> p{i, j, k};
            std::array<int64_t, 3> q = p;
            ++q[static_cast<std::size_t>(a)];
            const int64_t pp = i + nx * j + sxy * k, pq = q[0] + nx * q[1] + sxy * q[2];
            const double vp = f[pp], vq = f[pq];
            const double t = std::clamp((iso - vp) / (vq - vp), 0.0, 1.0);
            Eigen::Vector3d ijk{double(i), double(j), double(k)};
            ijk[a] += t;
            const Eigen::Vector3d x = origin + M * ijk;
            const Eigen::Vector3d grad = gradient_to_world * ((1.0 - t) * node_gradient(f, p[0], p[1], p[2], dims) +
                                                              t * node_gradient(f, q[0], q[1], q[2], dims));
            const bool p_inside = inside[static_cast<std::size_t>(pp)] != 0;
            Eigen::Vector3d n = -grad;
            if (!(n.norm() > 1e-30) || !n.allFinite()) n = (p_inside ? 1.0 : -1.0) * M.col(a);
            n.normalize();
            std::array<int64_t, 3> cell{};
            Eigen::Vector3d frac;
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
            const double wx[2] = {1.0 - frac[0], frac[0]}, wy[2] = {1.0 - frac[1], frac[1]}, wz[2] = {1.0 - frac[2], frac[2]};
            for (int c = 0; c < 8; ++c)
              mesh.grid_weights[8 * v + static_cast<std::size_t>(c)] = static_cast<float>(wx[c & 1] * wy[(c >> 1) & 1] * wz[c >> 2]);
            ++v;
          }
        }
      }

      // Triangles of the cells between slices k and k + 1. Walking a row of cells, id[r] is the
      // first vertex id at node i of the cell's node row r; an edge's id adds the crossed edges
      // before it at its node (lower axes) and, for a node at i + 1, those of node i.
      if (k + 1 == nz) continue;
      uint32_t* out = mesh.triangles.data() + 3 * tfirst[static_cast<std::size_t>(k)];
      for (int64_t j = 0; j + 1 < ny; ++j) {
        const uint8_t* c = cases.get() + nx * j + sxy * k;
        const uint8_t* e[4] = {edges.get() + nx * j + sxy * k, edges.get() + nx * (j + 1) + sxy * k,
                               edges.get() + nx * j + sxy * (k + 1), edges.get() + nx * (j + 1) + sxy * (k + 1)};
        uint32_t id[4] = {row_first[static_cast<std::size_t>(j)], row_first[static_cast<std::size_t>(j + 1)],
                          row_first[static_cast<std::size_t>(ny + j)], row_first[static_cast<std::size_t>(ny + j + 1)]};
        // Only cells touching a node with a crossed edge can have triangles; before the first such
        // node no id advances.
        int64_t lo = nx, hi = -1;
        for (const int64_t r : {j + ny * k, j + 1 + ny * k, j + ny * (k + 1), j + 1 + ny * (k + 1)}) {
          lo = std::min<int64_t>(lo, row_lo[static_cast<std::size_t>(r)]);
          hi = std::max<int64_t>(hi, row_hi[static_cast<std::size_t>(r)]);
        }
        for (int64_t i = std::max<int64_t>(lo - 1, 0); i <= std::min(hi, nx - 2); ++i) {
          const unsigned config = c[i];
          const int nt = table.triangle_count[config];
          for (int t = 0; t < nt; ++t, out += 3)
            for (int m = 0; m < 3; ++m) {
              const auto ce = static_cast<std::size_t>(table.triangles[config][static_cast<std::size_t>(t)][static_cast<std::size_t>(m)]);
              const unsigned r = edge_row[ce], dx = edge_dx[ce];
              const uint8_t fl = e[r][i + dx];
              assert((fl >> edge_axis[ce]) & 1);
              const uint32_t vid = id[r] + (dx ? kPop3[e[r][i]] : 0u) + kPop3[fl & ((1u << edge_axis[ce]) - 1u)];
              out[flip && m > 0 ? 3 - m : m] = vid;
            }
          for (int r = 0; r < 4; ++r) id[r] += kPop3[e[r][i]];
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
