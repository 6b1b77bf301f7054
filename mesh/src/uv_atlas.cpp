#include "ctsurg/mesh/uv_atlas.h"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <numbers>
#include <numeric>
#include <unordered_map>

#include "ctsurg/core/error.h"

namespace ctsurg {

namespace {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;

// In-plane basis (e1, e2) of each axis with e1 x e2 = axis, so a triangle facing the axis projects
// counter-clockwise.
constexpr std::array<std::array<int, 2>, 6> kAxisBasis{{{1, 2}, {2, 1}, {2, 0}, {0, 2}, {0, 1}, {1, 0}}};
Vec3 axis_vector(int a) {
  Vec3 v = Vec3::Zero();
  v[a / 2] = (a % 2 == 0) ? 1.0 : -1.0;
  return v;
}
Vec2 project(const Vec3& p, int axis) {
  return {p[kAxisBasis[static_cast<std::size_t>(axis)][0]], p[kAxisBasis[static_cast<std::size_t>(axis)][1]]};
}

using Tri2 = std::array<Vec2, 3>;

// Triangle shrunk towards its centroid by a relative 1e-4: triangles that only touch do not overlap.
Tri2 shrunk(const Tri2& t) {
  const Vec2 c = (t[0] + t[1] + t[2]) / 3.0;
  return {c + (t[0] - c) * (1.0 - 1e-4), c + (t[1] - c) * (1.0 - 1e-4), c + (t[2] - c) * (1.0 - 1e-4)};
}

// Separating-axis test of two 2D triangles: true when their interiors overlap.
bool triangles_overlap(const Tri2& a, const Tri2& b) {
  const auto separated = [](const Tri2& p, const Tri2& q) {
    for (int e = 0; e < 3; ++e) {
      const Vec2 d = p[static_cast<std::size_t>((e + 1) % 3)] - p[static_cast<std::size_t>(e)];
      const Vec2 n(-d.y(), d.x());
      double pmin = 1e300, pmax = -1e300, qmin = 1e300, qmax = -1e300;
      for (int i = 0; i < 3; ++i) {
        const double x = n.dot(p[static_cast<std::size_t>(i)]), y = n.dot(q[static_cast<std::size_t>(i)]);
        pmin = std::min(pmin, x), pmax = std::max(pmax, x), qmin = std::min(qmin, y), qmax = std::max(qmax, y);
      }
      if (pmax <= qmin || qmax <= pmin) return true;
    }
    return false;
  };
  return !separated(a, b) && !separated(b, a);
}

constexpr std::size_t kSmallChartTriangles = 8;  // charts with fewer triangles try to merge
constexpr double kMergeAngleDeg = 80.0;          // ... into a neighbour whose axis is within this

struct Chart {
  int axis = 0;
  std::vector<uint32_t> tris;
  std::vector<uint32_t> verts;                   // input vertices, in order of first use
  std::vector<Vec2> pos;                         // layout position (mm) of each of verts, in the chart's frame, min corner at 0
  std::vector<std::array<uint32_t, 3>> corners;  // per triangle of tris, its corners as indices into verts
  double w = 0.0, h = 0.0;                       // extent, mm
};

// Placement of every chart at density s; false when they do not fit.
bool shelf_pack(const std::vector<Chart>& charts, const std::vector<std::size_t>& order, double s, int size, int pad,
                std::vector<std::array<int, 2>>& corner) {
  corner.assign(charts.size(), {0, 0});
  int x = pad, y = pad, shelf_h = 0;
  for (const std::size_t c : order) {
    const int wt = static_cast<int>(std::ceil(charts[c].w * s)) + 1, ht = static_cast<int>(std::ceil(charts[c].h * s)) + 1;
    if (wt + 2 * pad > size) return false;
    if (x + wt + pad > size) {
      x = pad;
      y += shelf_h + pad;
      shelf_h = 0;
    }
    if (y + ht + pad > size) return false;
    corner[c] = {x, y};
    x += wt + pad;
    shelf_h = std::max(shelf_h, ht);
  }
  return true;
}

// Chart vertex i in the chart's texel frame at density s: content in [0.5, extent * s + 0.5].
Vec2 chart_texel(const Chart& c, std::size_t i, double s) { return {c.pos[i].x() * s + 0.5, (c.h - c.pos[i].y()) * s + 0.5}; }

// First-fit packing of the charts' shapes on a raster of b x b texel blocks (b = size / 512, at
// least 1), so that small charts fill the holes and bays of large ones: a chart covers the blocks
// of its triangles' bounding boxes; it is placed, largest first, at the first block position (rows
// from the top, then columns) where its cover, grown by D = ceil(pad / b) blocks, meets no block
// already covered and stays inside the atlas. Cover blocks of two charts are then more than D
// blocks apart, so their texels are at least pad apart, and pad from the border. The scan jumps
// past the last covered block of a colliding row segment (kept per row), so it stays fast.
// origin[c] = texel offset of chart c's frame. False when some chart finds no place.
bool raster_pack(const std::vector<Chart>& charts, double s, int size, int pad, std::vector<Vec2>& origin) {
  const int b = std::max(1, size / 512), nb = size / b, D = (pad + b - 1) / b;
  struct Mask {
    int w = 0, h = 0;  // cover size in blocks
    std::vector<std::vector<std::pair<int, int>>> cover,
        grown;  // per row: runs [a, b) of the cover, and of the grown cover (offset D)
  };
  std::vector<Mask> masks(charts.size());
  std::vector<std::size_t> order(charts.size());
  for (std::size_t c = 0; c < charts.size(); ++c) {
    Mask& m = masks[c];
    m.w = static_cast<int>(std::floor((charts[c].w * s + 0.5) / b)) + 1;
    m.h = static_cast<int>(std::floor((charts[c].h * s + 0.5) / b)) + 1;
    if (m.w + 2 * D > nb || m.h + 2 * D > nb) return false;
    std::vector<uint8_t> cells(static_cast<std::size_t>(m.w) * static_cast<std::size_t>(m.h), 0);
    for (const auto& tri : charts[c].corners) {
      Vec2 lo(1e300, 1e300), hi(-1e300, -1e300);
      for (const uint32_t v : tri) {
        const Vec2 q = chart_texel(charts[c], v, s);
        lo = lo.cwiseMin(q), hi = hi.cwiseMax(q);
      }
      const int x0 = std::clamp(static_cast<int>(std::floor(lo.x() / b)), 0, m.w - 1),
                x1 = std::clamp(static_cast<int>(std::floor(hi.x() / b)), 0, m.w - 1);
      const int y0 = std::clamp(static_cast<int>(std::floor(lo.y() / b)), 0, m.h - 1),
                y1 = std::clamp(static_cast<int>(std::floor(hi.y() / b)), 0, m.h - 1);
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x)
          cells[static_cast<std::size_t>(y) * static_cast<std::size_t>(m.w) + static_cast<std::size_t>(x)] = 1;
    }
    const int gw = m.w + 2 * D, gh = m.h + 2 * D;
    std::vector<uint8_t> grown(static_cast<std::size_t>(gw) * static_cast<std::size_t>(gh), 0);
    for (int y = 0; y < m.h; ++y)
      for (int x = 0; x < m.w; ++x)
        if (cells[static_cast<std::size_t>(y) * static_cast<std::size_t>(m.w) + static_cast<std::size_t>(x)])
          for (int dy = 0; dy <= 2 * D; ++dy)
            for (int dx = 0; dx <= 2 * D; ++dx)
              grown[static_cast<std::size_t>(y + dy) * static_cast<std::size_t>(gw) + static_cast<std::size_t>(x + dx)] = 1;
    const auto runs = [](const std::vector<uint8_t>& bits, int w, int h) {
      std::vector<std::vector<std::pair<int, int>>> out(static_cast<std::size_t>(h));
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w;) {
          if (!bits[static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)]) {
            ++x;
            continue;
          }
          int e = x;
          while (e < w && bits[static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(e)]) ++e;
          out[static_cast<std::size_t>(y)].emplace_back(x, e);
          x = e;
        }
      return out;
    };
    m.cover = runs(cells, m.w, m.h);
    m.grown = runs(grown, gw, gh);
    order[c] = c;
  }
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t c) {
    return static_cast<int64_t>(masks[a].w) * masks[a].h > static_cast<int64_t>(masks[c].w) * masks[c].h;
  });
  // last[y][x]: the largest covered block index <= x in row y, or -1.
  std::vector<std::vector<int32_t>> last(static_cast<std::size_t>(nb), std::vector<int32_t>(static_cast<std::size_t>(nb), -1));
  std::vector<std::vector<uint8_t>> covered(static_cast<std::size_t>(nb), std::vector<uint8_t>(static_cast<std::size_t>(nb), 0));
  origin.assign(charts.size(), Vec2::Zero());
  for (const std::size_t c : order) {
    const Mask& m = masks[c];
    const int gw = m.w + 2 * D, gh = m.h + 2 * D;
    bool placed = false;
    for (int py = 0; py + gh <= nb && !placed; ++py) {
      int px = 0;
      while (px + gw <= nb) {
        int jump = -1;
        for (int r = 0; r < gh && jump < 0; ++r)
          for (const auto& [a, e] : m.grown[static_cast<std::size_t>(r)]) {
            const int l = last[static_cast<std::size_t>(py + r)][static_cast<std::size_t>(px + e - 1)];
            if (l >= px + a) {
              jump = l - a + 1;
              break;
            }
          }
        if (jump < 0) {
          placed = true;
          break;
        }
        px = jump;
      }
      if (!placed) continue;
      for (int r = 0; r < m.h; ++r) {
        const auto row = static_cast<std::size_t>(py + D + r);
        for (const auto& [a, e] : m.cover[static_cast<std::size_t>(r)])
          for (int x = a; x < e; ++x) covered[row][static_cast<std::size_t>(px + D + x)] = 1;
        int32_t l = -1;
        for (int x = 0; x < nb; ++x)
          last[row][static_cast<std::size_t>(x)] = l = covered[row][static_cast<std::size_t>(x)] ? x : l;
      }
      origin[c] = Vec2(static_cast<double>((px + D) * b), static_cast<double>((py + D) * b));
    }
    if (!placed) return false;
  }
  return true;
}

}  // namespace

UvAtlas build_uv_atlas(const std::vector<float>& vertices, const std::vector<uint32_t>& triangles,
                       const UvAtlasOptions& options) {
  if (options.size_px < 16 || options.size_px > 16384) throw InputError("uv atlas", "size_px", "must be in 16 .. 16384");
  if (options.padding_px < 1 || options.padding_px > options.size_px / 8) {
    throw InputError("uv atlas", "padding_px", "must be in 1 .. size / 8");
  }
  if (!(options.max_angle_deg >= 1.0 && options.max_angle_deg <= 85.0))
    throw InputError("uv atlas", "max_angle_deg", "must be in 1 .. 85");
  const std::size_t nv = vertices.size() / 3, nf = triangles.size() / 3;
  if (nv == 0 || nf == 0) throw InputError("uv atlas", "mesh", "the mesh is empty");
  const auto P = [&](uint32_t v) { return Vec3(vertices[3 * v], vertices[3 * v + 1], vertices[3 * v + 2]); };
  const auto corner_of = [&](std::size_t t, int c) { return triangles[3 * t + static_cast<std::size_t>(c)]; };

  // Unit normals and each triangle's best axis.
  std::vector<Vec3> normal(nf);
  std::vector<int> best_axis(nf);
  std::vector<double> alignment(nf);
  for (std::size_t t = 0; t < nf; ++t) {
    const Vec3 n = (P(corner_of(t, 1)) - P(corner_of(t, 0))).cross(P(corner_of(t, 2)) - P(corner_of(t, 0)));
    normal[t] = n.norm() > 0.0 ? Vec3(n.normalized()) : Vec3(0.0, 0.0, 1.0);
    int best = 0;
    for (int a = 1; a < 6; ++a)
      if (normal[t].dot(axis_vector(a)) > normal[t].dot(axis_vector(best))) best = a;
    best_axis[t] = best;
    alignment[t] = normal[t].dot(axis_vector(best));
  }

  // Edge adjacency: (min vertex, max vertex, triangle) sorted, so triangles sharing an edge are adjacent.
  std::vector<std::array<uint32_t, 3>> edges;
  edges.reserve(3 * nf);
  for (std::size_t t = 0; t < nf; ++t)
    for (int c = 0; c < 3; ++c) {
      const uint32_t a = corner_of(t, c), b = corner_of(t, (c + 1) % 3);
      edges.push_back({std::min(a, b), std::max(a, b), static_cast<uint32_t>(t)});
    }
  std::sort(edges.begin(), edges.end());
  std::vector<std::vector<uint32_t>> neighbours(nf);
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j][0] == edges[i][0] && edges[j][1] == edges[i][1]) ++j;
    for (std::size_t a = i; a < j; ++a)
      for (std::size_t b = i; b < j; ++b)
        if (a != b) neighbours[edges[a][2]].push_back(edges[b][2]);
    i = j;
  }

  // Seeds, best aligned first.
  std::vector<uint32_t> seeds(nf);
  std::iota(seeds.begin(), seeds.end(), 0u);
  std::stable_sort(seeds.begin(), seeds.end(), [&](uint32_t a, uint32_t b) { return alignment[a] > alignment[b]; });
  const double cos_max = std::cos(options.max_angle_deg * std::numbers::pi / 180.0);

  std::vector<int32_t> chart_of(nf, -1);
  std::vector<Chart> charts;
  double mean_edge = 0.0;
  for (std::size_t t = 0; t < nf; ++t) mean_edge += (P(corner_of(t, 1)) - P(corner_of(t, 0))).norm();
  mean_edge = std::max(mean_edge / static_cast<double>(nf), 1e-9);
  const double cell = 2.0 * mean_edge;  // hash-grid cell for the overlap test, mm
  // Hash grid per chart: cell -> the chart's triangles whose projected box touches it.
  std::vector<std::unordered_map<int64_t, std::vector<uint32_t>>> grids;
  const auto proj = [&](uint32_t t, int axis) {
    return Tri2{project(P(corner_of(t, 0)), axis), project(P(corner_of(t, 1)), axis), project(P(corner_of(t, 2)), axis)};
  };
  const auto for_cells = [&](const Tri2& tri, auto&& f) {
    Vec2 lo = tri[0].cwiseMin(tri[1]).cwiseMin(tri[2]), hi = tri[0].cwiseMax(tri[1]).cwiseMax(tri[2]);
    const auto i0 = static_cast<int64_t>(std::floor(lo.x() / cell)), i1 = static_cast<int64_t>(std::floor(hi.x() / cell));
    const auto j0 = static_cast<int64_t>(std::floor(lo.y() / cell)), j1 = static_cast<int64_t>(std::floor(hi.y() / cell));
    for (int64_t j = j0; j <= j1; ++j)
      for (int64_t i = i0; i <= i1; ++i) f((j << 32) ^ (i & 0xffffffff));
  };
  const auto overlaps_chart = [&](uint32_t t, std::size_t c) {
    const int axis = charts[c].axis;
    const Tri2 a = shrunk(proj(t, axis));
    bool hit = false;
    for_cells(a, [&](int64_t key) {
      if (hit) return;
      const auto it = grids[c].find(key);
      if (it == grids[c].end()) return;
      for (const uint32_t u : it->second)
        if (triangles_overlap(a, shrunk(proj(u, axis)))) {
          hit = true;
          return;
        }
    });
    return hit;
  };
  const auto add = [&](uint32_t t, std::size_t c) {
    chart_of[t] = static_cast<int32_t>(c);
    charts[c].tris.push_back(t);
    for_cells(proj(t, charts[c].axis), [&](int64_t key) { grids[c][key].push_back(t); });
  };
  for (const uint32_t seed : seeds) {
    if (chart_of[seed] >= 0) continue;
    const std::size_t id = charts.size();
    charts.emplace_back().axis = best_axis[seed];
    grids.emplace_back();
    const Vec3 axis = axis_vector(charts[id].axis);
    add(seed, id);
    std::deque<uint32_t> queue{seed};
    while (!queue.empty()) {
      const uint32_t t = queue.front();
      queue.pop_front();
      for (const uint32_t u : neighbours[t]) {
        if (chart_of[u] >= 0 || normal[u].dot(axis) < cos_max || overlaps_chart(u, id)) continue;
        add(u, id);
        queue.push_back(u);
      }
    }
  }

  // Small charts (a few triangles at sharp features of a coarse surface, where no axis suits the
  // neighbourhood) cost a seam and padding each: merge each into the neighbouring chart whose axis
  // suits all its triangles best, when every one is within kMergeAngleDeg of that axis and the
  // projection stays free of overlap. Charts are visited in order; a merged chart is left empty.
  const double cos_merge = std::cos(kMergeAngleDeg * std::numbers::pi / 180.0);
  for (std::size_t c = 0; c < charts.size(); ++c) {
    if (charts[c].tris.empty() || charts[c].tris.size() >= kSmallChartTriangles) continue;
    std::vector<std::size_t> candidates;
    for (const uint32_t t : charts[c].tris)
      for (const uint32_t u : neighbours[t])
        if (chart_of[u] != static_cast<int32_t>(c)) candidates.push_back(static_cast<std::size_t>(chart_of[u]));
    std::sort(candidates.begin(), candidates.end());
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    double best_score = -1.0;
    std::size_t best = c;
    for (const std::size_t d : candidates) {
      const Vec3 axis = axis_vector(charts[d].axis);
      double score = 0.0, worst = 1.0;
      for (const uint32_t t : charts[c].tris) score += normal[t].dot(axis), worst = std::min(worst, normal[t].dot(axis));
      if (worst >= cos_merge && score > best_score) best_score = score, best = d;
    }
    if (best == c) continue;
    bool overlap = false;
    for (const uint32_t t : charts[c].tris) overlap = overlap || overlaps_chart(t, best);
    // The merged triangles must not overlap one another in the new projection either.
    for (std::size_t a = 0; a < charts[c].tris.size() && !overlap; ++a)
      for (std::size_t b = a + 1; b < charts[c].tris.size() && !overlap; ++b)
        overlap = triangles_overlap(shrunk(proj(charts[c].tris[a], charts[best].axis)),
                                    shrunk(proj(charts[c].tris[b], charts[best].axis)));
    if (overlap) continue;
    for (const uint32_t t : charts[c].tris) add(t, best);
    charts[c].tris.clear();
    grids[c].clear();
  }
  // Drop the emptied charts, renumbering in order.
  {
    std::vector<int32_t> renumber(charts.size(), -1);
    std::vector<Chart> kept;
    for (std::size_t c = 0; c < charts.size(); ++c)
      if (!charts[c].tris.empty()) renumber[c] = static_cast<int32_t>(kept.size()), kept.push_back(std::move(charts[c]));
    charts = std::move(kept);
    for (int32_t& c : chart_of) c = renumber[static_cast<std::size_t>(c)];
  }

  // Per-chart vertices, rotation to principal axes, landscape.
  double total_area = 0.0;
  for (Chart& c : charts) {
    std::unordered_map<uint32_t, uint32_t> local;
    for (const uint32_t t : c.tris) {
      std::array<uint32_t, 3> corners{};
      for (int k = 0; k < 3; ++k) {
        const auto [it, added] = local.emplace(corner_of(t, k), static_cast<uint32_t>(c.verts.size()));
        if (added) c.verts.push_back(corner_of(t, k));
        corners[static_cast<std::size_t>(k)] = it->second;
      }
      c.corners.push_back(corners);
    }
    std::vector<Vec2> q(c.verts.size());
    Vec2 mean = Vec2::Zero();
    for (std::size_t i = 0; i < q.size(); ++i) mean += (q[i] = project(P(c.verts[i]), c.axis));
    mean /= static_cast<double>(q.size());
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
    for (const Vec2& p : q) cov += (p - mean) * (p - mean).transpose();
    const double angle = 0.5 * std::atan2(2.0 * cov(0, 1), cov(0, 0) - cov(1, 1));
    const auto box = [&](double a) {
      const Eigen::Rotation2Dd r(-a);
      Vec2 lo(1e300, 1e300), hi(-1e300, -1e300);
      for (const Vec2& p : q) {
        const Vec2 x = r * p;
        lo = lo.cwiseMin(x), hi = hi.cwiseMax(x);
      }
      return std::pair{lo, hi};
    };
    auto [lo0, hi0] = box(0.0);
    auto [lo1, hi1] = box(angle);
    const double rot = (hi1 - lo1).prod() < (hi0 - lo0).prod() ? angle : 0.0;
    const Eigen::Rotation2Dd r(-rot);
    c.pos.resize(q.size());
    Vec2 lo(1e300, 1e300), hi(-1e300, -1e300);
    for (std::size_t i = 0; i < q.size(); ++i) {
      c.pos[i] = r * q[i];
      lo = lo.cwiseMin(c.pos[i]), hi = hi.cwiseMax(c.pos[i]);
    }
    const bool turn = (hi.y() - lo.y()) > (hi.x() - lo.x());  // a quarter turn keeps the orientation
    for (Vec2& p : c.pos) {
      p -= lo;
      if (turn) p = Vec2(hi.y() - lo.y() - p.y(), p.x());
    }
    c.w = turn ? hi.y() - lo.y() : hi.x() - lo.x();
    c.h = turn ? hi.x() - lo.x() : hi.y() - lo.y();
    for (const uint32_t t : c.tris)
      total_area += std::abs(normal[t].dot(axis_vector(c.axis))) * 0.5 *
                    (P(corner_of(t, 1)) - P(corner_of(t, 0))).cross(P(corner_of(t, 2)) - P(corner_of(t, 0))).norm();
  }

  // Packing: the largest common density that fits, by bisection.
  std::vector<std::size_t> order(charts.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  const int size = options.size_px, pad = options.padding_px;
  std::vector<std::array<int, 2>> corner;
  const double s_max = size / std::sqrt(std::max(total_area, 1e-12));  // every texel filled
  double s_hi = s_max, s_lo = 0.0;
  const auto sort_for = [&](double s) {
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      const double ha = std::ceil(charts[a].h * s), hb = std::ceil(charts[b].h * s);
      if (ha != hb) return ha > hb;
      return std::ceil(charts[a].w * s) > std::ceil(charts[b].w * s);
    });
  };
  for (int it = 0; it < 40; ++it) {
    const double s = 0.5 * (s_lo + s_hi);
    std::iota(order.begin(), order.end(), std::size_t{0});
    sort_for(s);
    if (shelf_pack(charts, order, s, size, pad, corner))
      s_lo = s;
    else
      s_hi = s;
  }
  std::iota(order.begin(), order.end(), std::size_t{0});
  sort_for(s_lo);
  if (s_lo <= 0.0 || !shelf_pack(charts, order, s_lo, size, pad, corner)) {
    throw RuntimeError("uv atlas: " + std::to_string(charts.size()) + " charts do not fit a " + std::to_string(size) +
                       " texel atlas with " + std::to_string(pad) + " texels of padding; use a larger size or less padding");
  }
  // Shape packing fills the holes of ring-shaped charts: bisect again from the shelf density
  // upwards and keep the denser layout.
  std::vector<Vec2> origin(charts.size());
  for (std::size_t ci = 0; ci < charts.size(); ++ci) {
    const int wt = static_cast<int>(std::ceil(charts[ci].w * s_lo)) + 1,
              ht = static_cast<int>(std::ceil(charts[ci].h * s_lo)) + 1;
    origin[ci] =
        Vec2(corner[ci][0] + 0.5 * (wt - charts[ci].w * s_lo) - 0.5, corner[ci][1] + 0.5 * (ht - charts[ci].h * s_lo) - 0.5);
  }
  double s = s_lo;
  std::vector<Vec2> raster_origin;
  if (raster_pack(charts, s_lo, size, pad, raster_origin)) {
    double r_lo = s_lo, r_hi = s_max;
    for (int it = 0; it < 16; ++it) {
      const double m = 0.5 * (r_lo + r_hi);
      std::vector<Vec2> trial;
      if (raster_pack(charts, m, size, pad, trial))
        r_lo = m;
      else
        r_hi = m;
    }
    if (r_lo > s_lo && raster_pack(charts, r_lo, size, pad, raster_origin)) {
      s = r_lo;
      origin = raster_origin;
    }
  }

  // New vertices, chart by chart; chart (x, y) mm -> texel origin + (x s + 0.5, (h - y) s + 0.5):
  // the chart's second axis runs up the image, so the bitangent (up) follows it and handedness is +1.
  UvAtlas atlas;
  atlas.size_px = size;
  atlas.texels_per_mm = s;
  atlas.chart_count = static_cast<int64_t>(charts.size());
  atlas.triangles.resize(3 * nf);
  atlas.triangle_chart = chart_of;
  double uv_area = 0.0;
  for (std::size_t ci = 0; ci < charts.size(); ++ci) {
    const Chart& c = charts[ci];
    const auto first = static_cast<uint32_t>(atlas.source_vertex.size());
    std::unordered_map<uint32_t, uint32_t> local;
    for (std::size_t i = 0; i < c.verts.size(); ++i) {
      local.emplace(c.verts[i], first + static_cast<uint32_t>(i));
      atlas.source_vertex.push_back(c.verts[i]);
      const Vec2 q = origin[ci] + chart_texel(c, i, s);
      atlas.uvs.push_back(static_cast<float>(q.x() / size));
      atlas.uvs.push_back(static_cast<float>(q.y() / size));
    }
    for (const uint32_t t : c.tris) {
      for (int k = 0; k < 3; ++k) atlas.triangles[3 * t + static_cast<std::size_t>(k)] = local.at(corner_of(t, k));
      const uint32_t* v = &atlas.triangles[3 * t];
      const Vec2 a(atlas.uvs[2 * v[0]], atlas.uvs[2 * v[0] + 1]), b(atlas.uvs[2 * v[1]], atlas.uvs[2 * v[1] + 1]),
          d(atlas.uvs[2 * v[2]], atlas.uvs[2 * v[2] + 1]);
      const Vec2 e1 = b - a, e2 = d - a;
      uv_area += 0.5 * std::abs(e1.x() * e2.y() - e1.y() * e2.x());
    }
  }
  atlas.fill_ratio = uv_area;
  return atlas;
}

SurfaceMesh apply_uv_atlas(const SurfaceMesh& mesh, const UvAtlas& atlas) {
  SurfaceMesh out;
  const std::size_t n = atlas.source_vertex.size();
  const auto copy = [&](const auto& from, auto& to, std::size_t width) {
    to.resize(width * n);
    for (std::size_t v = 0; v < n; ++v)
      for (std::size_t c = 0; c < width; ++c) to[width * v + c] = from[width * atlas.source_vertex[v] + c];
  };
  copy(mesh.vertices, out.vertices, 3);
  copy(mesh.normals, out.normals, 3);
  copy(mesh.grid_cell, out.grid_cell, 3);
  copy(mesh.grid_weights, out.grid_weights, 8);
  copy(mesh.nearest_node, out.nearest_node, 3);
  out.triangles = atlas.triangles;
  out.lattice = mesh.lattice;
  out.iso = mesh.iso;
  out.quantity = mesh.quantity;
  out.source_dataset = mesh.source_dataset;
  out.uvs = atlas.uvs;
  out.source_vertex = atlas.source_vertex;
  out.source_vertex_count = mesh.vertex_count();
  return out;
}

}  // namespace ctsurg
