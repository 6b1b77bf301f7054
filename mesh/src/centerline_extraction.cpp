#include "ctsurg/mesh/centerline_extraction.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/memory_guard.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>
#include <queue>
#include <set>
#include <sstream>
#include <utility>

namespace ctsurg {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kTaubinLambda = 0.5, kTaubinMu = -0.53;

// ---------------------------------------------------------------------------------------------------
// The working lattice: the mask's bounding box with one voxel of padding on every side (always
// background, so 26-neighbours of object voxels never leave it). Crop index c <-> image index c + lo.
struct Crop {
  std::array<int64_t, 3> lo{};  // image index of crop voxel (0, 0, 0) (may be -1)
  std::array<int64_t, 3> d{};   // crop dims
  std::array<int64_t, 26> off{};  // flat offsets of the 26 neighbours, (dz, dy, dx) lexicographic
  std::array<int64_t, 6> off6{};
  int64_t n = 0;
  int64_t flat(int64_t a, int64_t b, int64_t c) const { return a + d[0] * (b + d[1] * c); }
  std::array<int64_t, 3> ijk(int64_t f) const { return {f % d[0], (f / d[0]) % d[1], f / (d[0] * d[1])}; }
};

// ---------------------------------------------------------------------------------------------------
// Simple points for the 26/6 topology (Bertrand & Malandain 1994, "A new characterization of
// three-dimensional simple points", Pattern Recognition Letters 15(2)). Positions in the 3x3x3 cube are
// (dx+1) + 3 (dy+1) + 9 (dz+1); 13 is the centre.
struct CubeTables {
  std::array<std::vector<int>, 27> adj26;    // 26-neighbours within the cube, centre excluded
  std::array<std::vector<int>, 27> adj6n18;  // 6-neighbours within N18, centre excluded
  std::array<bool, 27> in18{};
  std::array<int, 6> faces{};
  CubeTables() {
    const auto pos = [](int x, int y, int z) { return (x + 1) + 3 * (y + 1) + 9 * (z + 1); };
    int nf = 0;
    for (int z = -1; z <= 1; ++z)
      for (int y = -1; y <= 1; ++y)
        for (int x = -1; x <= 1; ++x) {
          const int p = pos(x, y, z), m = std::abs(x) + std::abs(y) + std::abs(z);
          in18[static_cast<std::size_t>(p)] = m >= 1 && m <= 2;
          if (m == 1) faces[static_cast<std::size_t>(nf++)] = p;
        }
    for (int z = -1; z <= 1; ++z)
      for (int y = -1; y <= 1; ++y)
        for (int x = -1; x <= 1; ++x) {
          const int p = pos(x, y, z);
          if (p == 13) continue;
          for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
              for (int dx = -1; dx <= 1; ++dx) {
                const int X = x + dx, Y = y + dy, Z = z + dz;
                if ((dx == 0 && dy == 0 && dz == 0) || std::abs(X) > 1 || std::abs(Y) > 1 || std::abs(Z) > 1) continue;
                const int q = pos(X, Y, Z);
                if (q == 13) continue;
                adj26[static_cast<std::size_t>(p)].push_back(q);
                if (std::abs(dx) + std::abs(dy) + std::abs(dz) == 1 && in18[static_cast<std::size_t>(p)] &&
                    in18[static_cast<std::size_t>(q)]) {
                  adj6n18[static_cast<std::size_t>(p)].push_back(q);
                }
              }
        }
  }
};

const CubeTables& cube_tables() {
  static const CubeTables t;
  return t;
}

// `cube` bit p set: position p is object.
bool is_simple(uint32_t cube) {
  const CubeTables& t = cube_tables();
  // One 26-component of the object in N26*.
  const uint32_t object = cube & ~(1u << 13);
  if (object == 0) return false;
  int stack[27];
  uint32_t seen = 0;
  int top = 0;
  const int first = std::countr_zero(object);
  stack[top++] = first;
  seen |= 1u << first;
  while (top > 0) {
    const int p = stack[--top];
    for (const int q : t.adj26[static_cast<std::size_t>(p)]) {
      if ((object >> q & 1u) && !(seen >> q & 1u)) {
        seen |= 1u << q;
        stack[top++] = q;
      }
    }
  }
  if (seen != object) return false;
  // One 6-component of the background in N18 that is 6-adjacent to the centre.
  int components = 0;
  seen = 0;
  for (const int f : t.faces) {
    if ((cube >> f & 1u) || (seen >> f & 1u)) continue;
    if (++components > 1) return false;
    top = 0;
    stack[top++] = f;
    seen |= 1u << f;
    while (top > 0) {
      const int p = stack[--top];
      for (const int q : t.adj6n18[static_cast<std::size_t>(p)]) {
        if (!(cube >> q & 1u) && !(seen >> q & 1u)) {
          seen |= 1u << q;
          stack[top++] = q;
        }
      }
    }
  }
  return components == 1;
}

// ---------------------------------------------------------------------------------------------------
// Squared distance transform of a sampled function along one line (Felzenszwalb & Huttenlocher 2012,
// algorithm DT(f)): d[q] = min_p w2 (q - p)^2 + f[p], arg[q] = that p. Infinite f[p] never belong to
// the lower envelope.
void distance_1d(const double* f, int64_t n, double w2, double* d, int64_t* arg, std::vector<int64_t>& v,
                 std::vector<double>& z) {
  int64_t k = -1;
  for (int64_t q = 0; q < n; ++q) {
    if (!(f[q] < kInf)) continue;
    if (k < 0) {
      k = 0;
      v[0] = q;
      z[0] = -kInf;
      z[1] = kInf;
      continue;
    }
    const auto meet = [&](int64_t p) {
      const double qd = double(q), pd = double(p);
      return ((f[q] + w2 * qd * qd) - (f[p] + w2 * pd * pd)) / (2.0 * w2 * (qd - pd));
    };
    double s = meet(v[static_cast<std::size_t>(k)]);
    while (s <= z[static_cast<std::size_t>(k)]) {
      --k;
      s = meet(v[static_cast<std::size_t>(k)]);
    }
    ++k;
    v[static_cast<std::size_t>(k)] = q;
    z[static_cast<std::size_t>(k)] = s;
    z[static_cast<std::size_t>(k + 1)] = kInf;
  }
  if (k < 0) {
    std::fill(d, d + n, kInf);
    std::fill(arg, arg + n, int64_t{0});
    return;
  }
  int64_t j = 0;
  for (int64_t q = 0; q < n; ++q) {
    while (z[static_cast<std::size_t>(j + 1)] < double(q)) ++j;
    const double dq = double(q - v[static_cast<std::size_t>(j)]);
    d[q] = w2 * dq * dq + f[v[static_cast<std::size_t>(j)]];
    arg[q] = v[static_cast<std::size_t>(j)];
  }
}

// Euclidean distance (mm) from every crop voxel's centre to the nearest source (source[v] != 0), and
// that source (`nearest`, a flat crop index: the feature transform, carried through the passes).
std::vector<double> distance_transform(const Crop& c, const std::vector<uint8_t>& source, const Eigen::Vector3d& spacing,
                                       std::vector<int64_t>& nearest) {
  std::vector<double> g(static_cast<std::size_t>(c.n));
  nearest.resize(static_cast<std::size_t>(c.n));
  for (int64_t i = 0; i < c.n; ++i) {
    g[static_cast<std::size_t>(i)] = source[static_cast<std::size_t>(i)] ? 0.0 : kInf;
    nearest[static_cast<std::size_t>(i)] = i;
  }
  const int64_t longest = std::max({c.d[0], c.d[1], c.d[2]});
  std::vector<double> line(static_cast<std::size_t>(longest)), out(static_cast<std::size_t>(longest)),
      z(static_cast<std::size_t>(longest + 1));
  std::vector<int64_t> v(static_cast<std::size_t>(longest)), arg(static_cast<std::size_t>(longest)),
      feature(static_cast<std::size_t>(longest));
  const std::array<int64_t, 3> stride{1, c.d[0], c.d[0] * c.d[1]};
  for (int axis = 0; axis < 3; ++axis) {
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    const double w2 = spacing[axis] * spacing[axis];
    const int64_t n = c.d[static_cast<std::size_t>(axis)];
    const int64_t st = stride[static_cast<std::size_t>(axis)];
    for (int64_t u = 0; u < c.d[static_cast<std::size_t>(a1)]; ++u)
      for (int64_t w = 0; w < c.d[static_cast<std::size_t>(a2)]; ++w) {
        const int64_t base = u * stride[static_cast<std::size_t>(a1)] + w * stride[static_cast<std::size_t>(a2)];
        for (int64_t q = 0; q < n; ++q) {
          line[static_cast<std::size_t>(q)] = g[static_cast<std::size_t>(base + q * st)];
          feature[static_cast<std::size_t>(q)] = nearest[static_cast<std::size_t>(base + q * st)];
        }
        distance_1d(line.data(), n, w2, out.data(), arg.data(), v, z);
        for (int64_t q = 0; q < n; ++q) {
          g[static_cast<std::size_t>(base + q * st)] = out[static_cast<std::size_t>(q)];
          nearest[static_cast<std::size_t>(base + q * st)] = feature[static_cast<std::size_t>(arg[static_cast<std::size_t>(q)])];
        }
      }
  }
  for (double& x : g) x = std::sqrt(x);
  return g;
}

// ---------------------------------------------------------------------------------------------------
// The skeleton and its graph.
struct Branch {
  int a = -1, b = -1;                  // nodes
  std::vector<int64_t> interior;       // crop voxels from a to b, nodes excluded
  double length_mm = 0.0;              // along centre(a), interior, centre(b)
  double min_dt = kInf;                // smallest DT of the interior
  int64_t min_voxel = -1;              // where
};

struct Graph {
  std::vector<int64_t> centre;         // each node's voxel (largest DT of its cluster)
  std::vector<uint8_t> junction;       // node is a cluster of degree >= 3 (or merged) voxels
  std::vector<int> degree;             // branch ends at each node
  std::vector<Branch> branches;
  std::vector<std::vector<int64_t>> rings;  // closed curves without a node
};

class Skeleton {
 public:
  Skeleton(const Crop& crop, std::vector<uint8_t> object, const std::vector<double>& dt, const Eigen::Vector3d& spacing)
      : c_(crop), s_(std::move(object)), dt_(dt), spacing_(spacing), node_of_(static_cast<std::size_t>(crop.n), -1),
        mark_(static_cast<std::size_t>(crop.n), 0), forced_(static_cast<std::size_t>(crop.n), 0) {
    for (int64_t i = 0; i < c_.n; ++i)
      if (s_[static_cast<std::size_t>(i)]) voxels_.push_back(i);
  }

  const std::vector<int64_t>& voxels() const { return voxels_; }
  bool has(int64_t v) const { return s_[static_cast<std::size_t>(v)] != 0; }
  void force_junction(int64_t v) { forced_[static_cast<std::size_t>(v)] = 1; }
  void remove(const std::vector<int64_t>& vs) {
    for (const int64_t v : vs) s_[static_cast<std::size_t>(v)] = 0;
    std::erase_if(voxels_, [&](int64_t v) { return !s_[static_cast<std::size_t>(v)]; });
  }
  int degree(int64_t v) const {
    int n = 0;
    for (const int64_t o : c_.off) n += s_[static_cast<std::size_t>(v + o)];
    return n;
  }
  Eigen::Vector3d mm(int64_t v) const {
    const auto q = c_.ijk(v);
    return Eigen::Vector3d(double(q[0]) * spacing_[0], double(q[1]) * spacing_[1], double(q[2]) * spacing_[2]);
  }

  Graph build() {
    Graph g;
    std::vector<int> deg(voxels_.size());
    for (std::size_t k = 0; k < voxels_.size(); ++k) deg[k] = degree(voxels_[k]);
    std::vector<int64_t> stack;
    // Nodes: junction clusters (26-connected voxels of degree >= 3 or merged) and end points.
    for (std::size_t k = 0; k < voxels_.size(); ++k) {
      const int64_t v = voxels_[k];
      if (node_of_[static_cast<std::size_t>(v)] >= 0) continue;
      const bool junction = deg[k] >= 3 || forced_[static_cast<std::size_t>(v)];
      if (!junction && deg[k] == 2) continue;
      const int id = static_cast<int>(g.centre.size());
      int64_t best = v;
      node_of_[static_cast<std::size_t>(v)] = id;
      if (junction) {
        stack.assign(1, v);
        while (!stack.empty()) {
          const int64_t u = stack.back();
          stack.pop_back();
          const double du = dt_[static_cast<std::size_t>(u)], db = dt_[static_cast<std::size_t>(best)];
          if (du > db || (du == db && u < best)) best = u;
          for (const int64_t o : c_.off) {
            const int64_t w = u + o;
            if (!s_[static_cast<std::size_t>(w)] || node_of_[static_cast<std::size_t>(w)] >= 0) continue;
            if (degree(w) >= 3 || forced_[static_cast<std::size_t>(w)]) {
              node_of_[static_cast<std::size_t>(w)] = id;
              stack.push_back(w);
            }
          }
        }
      }
      g.centre.push_back(best);
      g.junction.push_back(junction ? 1 : 0);
    }
    // Branches: from every node voxel into each neighbour outside the node.
    std::set<std::pair<int, int>> direct;
    for (const int64_t v : voxels_) {
      const int n = node_of_[static_cast<std::size_t>(v)];
      if (n < 0) continue;
      for (const int64_t o : c_.off) {
        const int64_t w = v + o;
        if (!s_[static_cast<std::size_t>(w)]) continue;
        const int m = node_of_[static_cast<std::size_t>(w)];
        if (m == n) continue;
        if (m >= 0) {
          if (n < m && direct.insert({n, m}).second) g.branches.push_back(finish({n, m, {}}, g));
          continue;
        }
        if (mark_[static_cast<std::size_t>(w)]) continue;
        Branch b;
        b.a = n;
        int64_t prev = v, cur = w;
        for (;;) {
          mark_[static_cast<std::size_t>(cur)] = 1;
          b.interior.push_back(cur);
          int64_t next = -1;
          for (const int64_t o2 : c_.off) {
            const int64_t x = cur + o2;
            if (s_[static_cast<std::size_t>(x)] && x != prev) {
              next = x;
              break;
            }
          }
          if (next < 0 || node_of_[static_cast<std::size_t>(next)] >= 0) {
            b.b = next < 0 ? n : node_of_[static_cast<std::size_t>(next)];
            break;
          }
          if (mark_[static_cast<std::size_t>(next)]) {  // cannot happen on a thin curve; stop safely
            b.b = n;
            break;
          }
          prev = cur;
          cur = next;
        }
        g.branches.push_back(finish(std::move(b), g));
      }
    }
    // Rings: closed curves of degree-2 voxels with no node.
    for (const int64_t v : voxels_) {
      if (node_of_[static_cast<std::size_t>(v)] >= 0 || mark_[static_cast<std::size_t>(v)]) continue;
      std::vector<int64_t> ring;
      stack.assign(1, v);
      mark_[static_cast<std::size_t>(v)] = 1;
      while (!stack.empty()) {
        const int64_t u = stack.back();
        stack.pop_back();
        ring.push_back(u);
        for (const int64_t o : c_.off) {
          const int64_t w = u + o;
          if (s_[static_cast<std::size_t>(w)] && !mark_[static_cast<std::size_t>(w)]) {
            mark_[static_cast<std::size_t>(w)] = 1;
            stack.push_back(w);
          }
        }
      }
      g.rings.push_back(std::move(ring));
    }
    for (const int64_t v : voxels_) {
      node_of_[static_cast<std::size_t>(v)] = -1;
      mark_[static_cast<std::size_t>(v)] = 0;
    }
    g.degree.assign(g.centre.size(), 0);
    for (const Branch& b : g.branches) {
      ++g.degree[static_cast<std::size_t>(b.a)];
      ++g.degree[static_cast<std::size_t>(b.b)];
    }
    return g;
  }

  // The branch's voxels from its start node's centre to its end node's centre.
  std::vector<int64_t> path(const Graph& g, const Branch& b) const {
    std::vector<int64_t> p;
    p.reserve(b.interior.size() + 2);
    p.push_back(g.centre[static_cast<std::size_t>(b.a)]);
    p.insert(p.end(), b.interior.begin(), b.interior.end());
    p.push_back(g.centre[static_cast<std::size_t>(b.b)]);
    return p;
  }

 private:
  Branch finish(Branch b, const Graph& g) const {
    Eigen::Vector3d prev = mm(g.centre[static_cast<std::size_t>(b.a)]);
    for (const int64_t v : b.interior) {
      const Eigen::Vector3d p = mm(v);
      b.length_mm += (p - prev).norm();
      prev = p;
      const double d = dt_[static_cast<std::size_t>(v)];
      if (d < b.min_dt || (d == b.min_dt && v < b.min_voxel)) {
        b.min_dt = d;
        b.min_voxel = v;
      }
    }
    b.length_mm += (mm(g.centre[static_cast<std::size_t>(b.b)]) - prev).norm();  // every node exists before tracing
    return b;
  }

  const Crop& c_;
  std::vector<uint8_t> s_;
  const std::vector<double>& dt_;
  Eigen::Vector3d spacing_;
  std::vector<int32_t> node_of_;
  std::vector<uint8_t> mark_, forced_;
  std::vector<int64_t> voxels_;
};

struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[static_cast<std::size_t>(x)] != x) x = parent[static_cast<std::size_t>(x)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(x)])];
    return x;
  }
  bool unite(int a, int b) {
    a = find(a);
    b = find(b);
    if (a == b) return false;
    parent[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);
    return true;
  }
};

std::string format_lps(const Eigen::Vector3d& p) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(1);
  s << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return s.str();
}

}  // namespace

void validate_centerline_options(const CenterlineOptions& o) {
  const auto factor = [](double v, const char* name, bool positive) {
    if (!std::isfinite(v) || v < 0.0 || (positive && v == 0.0)) {
      throw InputError(name, "", std::string("must be finite and ") + (positive ? "> 0" : ">= 0") + ", got " +
                                     std::to_string(v));
    }
  };
  factor(o.spur_length_factor, "--spur-length", false);
  factor(o.junction_merge_factor, "--junction-merge", false);
  factor(o.min_length_factor, "--min-length", true);
  if (o.smoothing_iterations < 0 || o.smoothing_iterations > 1000) {
    throw InputError("--smoothing", "", "must be in [0, 1000], got " + std::to_string(o.smoothing_iterations));
  }
  if (!(o.radius_correction_voxels >= 0.0 && o.radius_correction_voxels <= 1.0)) {
    throw InputError("--radius-correction", "", "must be in [0, 1] voxel, got " + std::to_string(o.radius_correction_voxels));
  }
}

std::string centerline_options_json(const CenterlineOptions& o) {
  nlohmann::ordered_json j;
  j["method"] = "distance-ordered 26/6 thinning on the exact EDT (mm), spur pruning, Taubin smoothing";
  j["spur_length_factor"] = o.spur_length_factor;
  j["junction_merge_factor"] = o.junction_merge_factor;
  j["smoothing_iterations"] = o.smoothing_iterations;
  j["min_length_factor"] = o.min_length_factor;
  j["radius_correction_voxels"] = o.radius_correction_voxels;
  j["keep_largest_component"] = o.keep_largest_component;
  j["break_loops"] = o.break_loops;
  return j.dump();
}

Centerline extract_centerline(const Volume<uint8_t>& mask, const CenterlineOptions& options, const std::string& file,
                              CenterlineReport* report_out) {
  validate_centerline_options(options);
  CenterlineReport report;
  const ImageGeometry& geo = mask.geometry;
  const Eigen::Vector3d sp = geo.spacing;
  const double h_max = sp.maxCoeff(), h_min = sp.minCoeff();

  // 1. Bounding box, crop, components.
  std::array<int64_t, 3> lo{geo.dims[0], geo.dims[1], geo.dims[2]}, hi{-1, -1, -1};
  for (int64_t k = 0; k < geo.dims[2]; ++k)
    for (int64_t j = 0; j < geo.dims[1]; ++j)
      for (int64_t i = 0; i < geo.dims[0]; ++i) {
        if (!mask.voxels[static_cast<std::size_t>(geo.flat_index(i, j, k))]) continue;
        ++report.mask_voxels;
        const std::array<int64_t, 3> q{i, j, k};
        for (std::size_t a = 0; a < 3; ++a) {
          lo[a] = std::min(lo[a], q[a]);
          hi[a] = std::max(hi[a], q[a]);
        }
      }
  if (report.mask_voxels == 0) throw InputError(file, "mask", "no non-zero voxel: the mask is empty");
  Crop c;
  for (std::size_t a = 0; a < 3; ++a) {
    c.lo[a] = lo[a] - 1;
    c.d[a] = hi[a] - lo[a] + 3;
  }
  c.n = c.d[0] * c.d[1] * c.d[2];
  check_allocation(static_cast<uint64_t>(c.n), 32, file, "mask (centerline working lattice)");
  {
    std::size_t k = 0, k6 = 0;
    for (int64_t dz = -1; dz <= 1; ++dz)
      for (int64_t dy = -1; dy <= 1; ++dy)
        for (int64_t dx = -1; dx <= 1; ++dx) {
          if (dx == 0 && dy == 0 && dz == 0) continue;
          const int64_t o = dx + c.d[0] * (dy + c.d[1] * dz);
          c.off[k++] = o;
          if (std::abs(dx) + std::abs(dy) + std::abs(dz) == 1) c.off6[k6++] = o;
        }
  }
  std::vector<uint8_t> object(static_cast<std::size_t>(c.n), 0);
  for (int64_t k = 1; k < c.d[2] - 1; ++k)
    for (int64_t j = 1; j < c.d[1] - 1; ++j)
      for (int64_t i = 1; i < c.d[0] - 1; ++i) {
        object[static_cast<std::size_t>(c.flat(i, j, k))] =
            mask.voxels[static_cast<std::size_t>(geo.flat_index(i + c.lo[0], j + c.lo[1], k + c.lo[2]))] != 0;
      }
  const auto world = [&](const Eigen::Vector3d& crop_ijk) {
    return geo.index_to_world(crop_ijk + Eigen::Vector3d(double(c.lo[0]), double(c.lo[1]), double(c.lo[2])));
  };
  const auto voxel_world = [&](int64_t v) {
    const auto q = c.ijk(v);
    return world(Eigen::Vector3d(double(q[0]), double(q[1]), double(q[2])));
  };

  std::vector<int64_t> stack;
  {
    std::vector<int32_t> comp(static_cast<std::size_t>(c.n), -1);
    std::vector<int64_t> sizes;
    for (int64_t v = 0; v < c.n; ++v) {
      if (!object[static_cast<std::size_t>(v)] || comp[static_cast<std::size_t>(v)] >= 0) continue;
      const int32_t id = static_cast<int32_t>(sizes.size());
      int64_t size = 0;
      stack.assign(1, v);
      comp[static_cast<std::size_t>(v)] = id;
      while (!stack.empty()) {
        const int64_t u = stack.back();
        stack.pop_back();
        ++size;
        for (const int64_t o : c.off) {
          const int64_t w = u + o;
          if (object[static_cast<std::size_t>(w)] && comp[static_cast<std::size_t>(w)] < 0) {
            comp[static_cast<std::size_t>(w)] = id;
            stack.push_back(w);
          }
        }
      }
      sizes.push_back(size);
    }
    std::vector<std::size_t> order(sizes.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return sizes[a] > sizes[b]; });
    for (const std::size_t o : order) report.component_sizes.push_back(sizes[o]);
    if (sizes.size() > 1) {
      if (!options.keep_largest_component) {
        std::string list;
        for (std::size_t k = 0; k < std::min<std::size_t>(order.size(), 10); ++k) {
          list += (k ? ", " : "") + std::to_string(sizes[order[k]]);
        }
        if (order.size() > 10) list += ", ...";
        throw InputError(file, "mask",
                         std::to_string(sizes.size()) + " separate pieces (26-connected) of " + list +
                             " voxels; a centerline needs one: clean the mask, or keep the largest piece "
                             "(keep_largest_component, ctsurg-centerline --keep-largest)");
      }
      const int32_t keep = static_cast<int32_t>(order[0]);
      for (int64_t v = 0; v < c.n; ++v) object[static_cast<std::size_t>(v)] = comp[static_cast<std::size_t>(v)] == keep;
    }
  }

  // Cavities: background not 6-connected to the crop's border is filled.
  {
    std::vector<uint8_t> outside(static_cast<std::size_t>(c.n), 0);
    stack.clear();
    for (int64_t v = 0; v < c.n; ++v) {
      const auto q = c.ijk(v);
      const bool border = q[0] == 0 || q[1] == 0 || q[2] == 0 || q[0] == c.d[0] - 1 || q[1] == c.d[1] - 1 || q[2] == c.d[2] - 1;
      if (border && !object[static_cast<std::size_t>(v)]) {
        outside[static_cast<std::size_t>(v)] = 1;
        stack.push_back(v);
      }
    }
    while (!stack.empty()) {
      const int64_t u = stack.back();
      stack.pop_back();
      const auto q = c.ijk(u);
      for (int a = 0; a < 3; ++a)
        for (int s = -1; s <= 1; s += 2) {
          const int64_t x = q[static_cast<std::size_t>(a)] + s;
          if (x < 0 || x >= c.d[static_cast<std::size_t>(a)]) continue;
          const int64_t w = u + s * (a == 0 ? 1 : a == 1 ? c.d[0] : c.d[0] * c.d[1]);
          if (!object[static_cast<std::size_t>(w)] && !outside[static_cast<std::size_t>(w)]) {
            outside[static_cast<std::size_t>(w)] = 1;
            stack.push_back(w);
          }
        }
    }
    for (int64_t v = 0; v < c.n; ++v) {
      if (!object[static_cast<std::size_t>(v)] && !outside[static_cast<std::size_t>(v)]) {
        object[static_cast<std::size_t>(v)] = 1;
        ++report.filled_cavity_voxels;
      }
    }
  }

  // 2. Distance transforms: `dt` to every background voxel, the image border a wall (orders the
  // thinning, sizes spurs and junctions); `nearest`, the feature transform of the background inside
  // the image (radii).
  std::vector<double> dt;
  std::vector<int64_t> nearest;
  {
    std::vector<uint8_t> source(static_cast<std::size_t>(c.n), 0);
    for (int64_t v = 0; v < c.n; ++v) source[static_cast<std::size_t>(v)] = !object[static_cast<std::size_t>(v)];
    dt = distance_transform(c, source, sp, nearest);
    bool any = false;
    for (int64_t v = 0; v < c.n; ++v) {
      if (object[static_cast<std::size_t>(v)]) continue;
      const auto q = c.ijk(v);
      bool inside = true;
      for (std::size_t a = 0; a < 3; ++a) {
        const int64_t x = q[a] + c.lo[a];
        inside = inside && x >= 0 && x < geo.dims[a];
      }
      source[static_cast<std::size_t>(v)] = inside;
      any = any || inside;
    }
    if (!any) {
      throw InputError(file, "mask", "every voxel of the image is inside the mask: no background to measure radii from");
    }
    (void)distance_transform(c, source, sp, nearest);
  }

  // 3. Distance-ordered homotopic thinning.
  {
    using Item = std::pair<double, int64_t>;
    std::priority_queue<Item, std::vector<Item>, std::greater<>> heap;
    std::vector<uint8_t> queued(static_cast<std::size_t>(c.n), 0);
    for (int64_t v = 0; v < c.n; ++v) {
      if (!object[static_cast<std::size_t>(v)]) continue;
      bool border = false;
      for (const int64_t o : c.off6) border = border || !object[static_cast<std::size_t>(v + o)];
      if (border) {
        heap.push({dt[static_cast<std::size_t>(v)], v});
        queued[static_cast<std::size_t>(v)] = 1;
      }
    }
    while (!heap.empty()) {
      const int64_t v = heap.top().second;
      heap.pop();
      queued[static_cast<std::size_t>(v)] = 0;
      if (!object[static_cast<std::size_t>(v)]) continue;
      uint32_t cube = 1u << 13;
      int neighbours = 0;
      for (std::size_t k = 0; k < 26; ++k) {
        if (object[static_cast<std::size_t>(v + c.off[k])]) {
          cube |= 1u << (k < 13 ? k : k + 1);
          ++neighbours;
        }
      }
      if (neighbours <= 1 || !is_simple(cube)) continue;  // curve end point, or deleting it changes topology
      object[static_cast<std::size_t>(v)] = 0;
      for (const int64_t o : c.off) {
        const int64_t w = v + o;
        if (object[static_cast<std::size_t>(w)] && !queued[static_cast<std::size_t>(w)]) {
          queued[static_cast<std::size_t>(w)] = 1;
          heap.push({dt[static_cast<std::size_t>(w)], w});
        }
      }
    }
  }
  Skeleton skel(c, std::move(object), dt, sp);
  report.skeleton_voxels = static_cast<int64_t>(skel.voxels().size());

  // 4. Graph: merge close junctions, prune spurs.
  const auto settle = [&]() {
    for (;;) {
      Graph g = skel.build();
      bool merged = false;
      for (const Branch& b : g.branches) {
        if (!g.junction[static_cast<std::size_t>(b.a)] || !g.junction[static_cast<std::size_t>(b.b)]) continue;
        const double r = std::max(dt[static_cast<std::size_t>(g.centre[static_cast<std::size_t>(b.a)])],
                                  dt[static_cast<std::size_t>(g.centre[static_cast<std::size_t>(b.b)])]);
        if (b.length_mm < std::max(options.junction_merge_factor * r, 2.0 * h_max) && !b.interior.empty()) {
          for (const int64_t v : b.interior) skel.force_junction(v);
          merged = true;
          ++report.merged_junctions;
        }
      }
      if (!merged) return g;
    }
  };
  const auto prune = [&]() {
    for (;;) {
      Graph g = settle();
      // Spurs, the least significant first: by the sum of the DT along them (length x radius, mm^2), so
      // that of two prongs at a vessel's end the one along the axis is kept and the one into a thin
      // corner of the staircase goes.
      std::vector<std::pair<double, std::size_t>> spurs;
      for (std::size_t k = 0; k < g.branches.size(); ++k) {
        const Branch& b = g.branches[k];
        const int da = g.degree[static_cast<std::size_t>(b.a)], db = g.degree[static_cast<std::size_t>(b.b)];
        const bool a_end = da == 1 && !g.junction[static_cast<std::size_t>(b.a)];
        const bool b_end = db == 1 && !g.junction[static_cast<std::size_t>(b.b)];
        if (a_end == b_end) continue;
        const int j = a_end ? b.b : b.a;
        if (g.degree[static_cast<std::size_t>(j)] < 3) continue;
        if (b.length_mm < options.spur_length_factor * dt[static_cast<std::size_t>(g.centre[static_cast<std::size_t>(j)])]) {
          double weight = dt[static_cast<std::size_t>(g.centre[static_cast<std::size_t>(a_end ? b.a : b.b)])];
          for (const int64_t v : b.interior) weight += dt[static_cast<std::size_t>(v)];
          spurs.push_back({weight, k});
        }
      }
      std::sort(spurs.begin(), spurs.end());
      std::vector<int> left = g.degree;
      std::vector<int64_t> drop;
      for (const auto& spur : spurs) {
        const Branch& b = g.branches[spur.second];
        const bool a_end = g.degree[static_cast<std::size_t>(b.a)] == 1 && !g.junction[static_cast<std::size_t>(b.a)];
        const int j = a_end ? b.b : b.a, e = a_end ? b.a : b.b;
        if (left[static_cast<std::size_t>(j)] <= 2) continue;
        --left[static_cast<std::size_t>(j)];
        drop.insert(drop.end(), b.interior.begin(), b.interior.end());
        drop.push_back(g.centre[static_cast<std::size_t>(e)]);
        ++report.pruned_spurs;
      }
      if (drop.empty()) return g;
      skel.remove(drop);
    }
  };
  Graph g = prune();

  // 5. Loops.
  const auto loops = [&](const Graph& gr) {
    std::vector<std::size_t> order(gr.branches.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return gr.branches[a].min_dt > gr.branches[b].min_dt; });
    UnionFind uf(gr.centre.size());
    std::vector<int64_t> cuts;  // the thinnest voxel of each loop
    for (const std::size_t k : order) {
      const Branch& b = gr.branches[k];
      if (!uf.unite(b.a, b.b) && b.min_voxel >= 0) cuts.push_back(b.min_voxel);
    }
    for (const auto& ring : gr.rings) {
      int64_t best = ring.front();
      for (const int64_t v : ring) {
        const double dv = dt[static_cast<std::size_t>(v)], db = dt[static_cast<std::size_t>(best)];
        if (dv < db || (dv == db && v < best)) best = v;
      }
      cuts.push_back(best);
    }
    return cuts;
  };
  std::vector<int64_t> cuts = loops(g);
  if (!cuts.empty()) {
    if (!options.break_loops) {
      const int64_t v = cuts.front();
      std::ostringstream s;
      s.precision(3);
      s << cuts.size() << (cuts.size() == 1 ? " loop" : " loops")
        << " in the skeleton (a tunnel through the mask: vessels touching, or a hole through a wall); the first "
           "at LPS "
        << format_lps(voxel_world(v)) << " mm, its thinnest point (radius " << dt[static_cast<std::size_t>(v)]
        << " mm); fix the mask, or cut each loop at its thinnest point (break_loops, ctsurg-centerline --break-loops)";
      throw InputError(file, "mask", s.str());
    }
    report.broken_loops = static_cast<int64_t>(cuts.size());
    skel.remove(cuts);
    g = prune();
    if (!loops(g).empty()) throw RuntimeError(file + ": mask: a loop of the skeleton could not be cut");
  }

  // 6. Join branches through nodes left with two branches; no tubular part.
  std::vector<std::vector<int64_t>> paths;
  std::vector<std::array<int, 2>> ends;
  for (const Branch& b : g.branches) {
    paths.push_back(skel.path(g, b));
    ends.push_back({b.a, b.b});
  }
  for (int n = 0; n < static_cast<int>(g.centre.size()); ++n) {
    std::vector<std::pair<std::size_t, int>> at;  // (branch, end)
    for (std::size_t k = 0; k < paths.size(); ++k)
      for (int e = 0; e < 2; ++e)
        if (!paths[k].empty() && ends[k][static_cast<std::size_t>(e)] == n) at.push_back({k, e});
    if (at.size() != 2 || at[0].first == at[1].first) continue;
    auto [k1, e1] = at[0];
    auto [k2, e2] = at[1];
    if (e1 == 0) {  // k1 must end at n
      std::reverse(paths[k1].begin(), paths[k1].end());
      std::swap(ends[k1][0], ends[k1][1]);
    }
    if (e2 == 1) {  // k2 must start at n
      std::reverse(paths[k2].begin(), paths[k2].end());
      std::swap(ends[k2][0], ends[k2][1]);
    }
    paths[k1].insert(paths[k1].end(), paths[k2].begin() + 1, paths[k2].end());
    ends[k1][1] = ends[k2][1];
    paths[k2].clear();
  }
  std::vector<int> node_id(g.centre.size(), -1);
  Centerline out;
  double max_dt = 0.0;
  for (const int64_t v : skel.voxels()) max_dt = std::max(max_dt, dt[static_cast<std::size_t>(v)]);
  double voxel_length = 0.0;
  for (const auto& p : paths)
    for (std::size_t i = 1; i < p.size(); ++i) voxel_length += (skel.mm(p[i]) - skel.mm(p[i - 1])).norm();
  if (voxel_length < options.min_length_factor * max_dt) {
    std::ostringstream s;
    s.precision(3);
    s << "no tubular part: the skeleton is " << voxel_length << " mm long for a largest inscribed radius of " << max_dt
      << " mm (under " << options.min_length_factor << " x the radius: a blob, not a vessel)";
    throw InputError(file, "mask", s.str());
  }

  // 7-8. Smooth each branch in mm, sample the radius.
  // Distance (mm) from a point (crop index) to the nearest background centre: the nearest sources of
  // the 8 voxels around it are the candidates (exact unless the point's own nearest source is nearer
  // to it than to all 8, which needs a boundary curved on the scale of a voxel). Interpolating the DT
  // instead would cut the ridge's peak: about 0.3 voxel too small on the tubes of the tests.
  const auto boundary_distance = [&](const Eigen::Vector3d& q) {
    double r = kInf;
    for (int corner = 0; corner < 8; ++corner) {
      std::array<int64_t, 3> v{};
      for (std::size_t a = 0; a < 3; ++a) {
        const double x = std::clamp(q[static_cast<Eigen::Index>(a)], 0.0, double(c.d[a] - 1));
        v[a] = std::min<int64_t>(static_cast<int64_t>(std::floor(x)) + (corner >> a & 1), c.d[a] - 1);
      }
      const auto s = c.ijk(nearest[static_cast<std::size_t>(c.flat(v[0], v[1], v[2]))]);
      const Eigen::Vector3d d = (Eigen::Vector3d(double(s[0]), double(s[1]), double(s[2])) - q).cwiseProduct(sp);
      r = std::min(r, d.norm());
    }
    return r;
  };
  out.branch_offsets.push_back(0);
  for (std::size_t k = 0; k < paths.size(); ++k) {
    if (paths[k].empty()) continue;
    std::array<int, 2> nodes{};
    for (std::size_t e = 0; e < 2; ++e) {
      int& id = node_id[static_cast<std::size_t>(ends[k][e])];
      if (id < 0) {
        id = static_cast<int>(out.node_count());
        const Eigen::Vector3d p = voxel_world(g.centre[static_cast<std::size_t>(ends[k][e])]);
        out.nodes.insert(out.nodes.end(), {p.x(), p.y(), p.z()});
      }
      nodes[e] = id;
    }
    std::vector<Eigen::Vector3d> q;
    for (const int64_t v : paths[k]) q.push_back(skel.mm(v));
    std::vector<Eigen::Vector3d> tmp = q;
    for (int it = 0; it < options.smoothing_iterations && q.size() > 2; ++it) {
      for (const double f : {kTaubinLambda, kTaubinMu}) {
        for (std::size_t i = 1; i + 1 < q.size(); ++i) tmp[i] = q[i] + f * (0.5 * (q[i - 1] + q[i + 1]) - q[i]);
        for (std::size_t i = 1; i + 1 < q.size(); ++i) q[i] = tmp[i];
      }
    }
    const std::size_t n = q.size();
    for (std::size_t i = 0; i < n; ++i) {
      Eigen::Vector3d p;
      if (i == 0 || i + 1 == n) {
        const int node = nodes[i == 0 ? 0 : 1];
        p = Eigen::Vector3d(out.nodes[static_cast<std::size_t>(3 * node)], out.nodes[static_cast<std::size_t>(3 * node + 1)],
                            out.nodes[static_cast<std::size_t>(3 * node + 2)]);
      } else {
        p = world(q[i].cwiseQuotient(sp));
      }
      out.points.insert(out.points.end(), {p.x(), p.y(), p.z()});
      Eigen::Vector3d t = q[std::min(i + 1, n - 1)] - q[i == 0 ? 0 : i - 1];
      t = t.norm() > 0.0 ? Eigen::Vector3d(t / t.norm()) : Eigen::Vector3d::Zero();
      double h2 = 0.0;
      for (int a = 0; a < 3; ++a) h2 += sp[a] * sp[a] * (1.0 - t[a] * t[a]);
      const double h = t.norm() > 0.0 ? std::sqrt(0.5 * h2) : std::cbrt(sp.prod());
      const double r = boundary_distance(q[i].cwiseQuotient(sp)) - options.radius_correction_voxels * h;
      out.radius.push_back(std::max(r, 0.25 * h_min));
      report.max_radius_mm = std::max(report.max_radius_mm, out.radius.back());
      if (i > 0) report.length_mm += (q[i] - q[i - 1]).norm();
    }
    out.branch_offsets.push_back(out.point_count());
    out.branch_nodes.insert(out.branch_nodes.end(), {nodes[0], nodes[1]});
  }
  out.label = 0;
  out.source_spacing_mm = {sp[0], sp[1], sp[2]};
  out.parameters = centerline_options_json(options);
  validate_centerline(out, file);
  if (report_out) *report_out = std::move(report);
  return out;
}

}  // namespace ctsurg
