// The medial-atom vessel model (sim/vessel, `kind: vessel`) against full nonlinear FEM of the same
// vessel (issue 20's "aorta pull"): time per frame, and how far the vessel model's centerline and drawn
// surface are from the FEM's deformed wall, near the tool and far from it.
//
// Geometry. A centerline (the aorta's, from ctsurg-centerline, or a synthetic straight tube), smoothed
// (`smooth` Laplacian passes, ends kept: the 3 mm voxel skeleton turns up to 45 degrees between points,
// which a 9 mm tube cannot follow without its inner wall folding) and resampled to even spacing with the
// same number of points; both models use that centerline (the vessel model reads it; it is written to
// OUT/<case>/centerline.h5). The FEM mesh is the hollow wall, inner radius r - t/2, outer r + t/2 (r the
// atoms' radius, linear in arc length), following a Catmull-Rom curve through the atoms with
// rotation-minimising frames (double reflection, Wang et al. 2008): rings of (layers x sectors) hexahedra,
// `per_atom` rings per atom spacing (a ring at every atom), each hexahedron split into 6 positively
// oriented tets (Kuhn, as fem_box_mesh.h). Tets between the first two atoms and between the last two
// are label 2: held (the nodes with that label, i.e. the wall up to atom 1 and from atom n-2).
//
// Loads (both models; the FEM static, one equilibrium per 1/60 s frame; the vessel's backward Euler at
// 1/60 s, damped, run until it rests):
//   pull   a grab centred on the axis at the middle atom moved 15 mm perpendicular to the axis over
//          0.25 s, held. FEM: sphere radius sqrt((r + t/2)^2 + (h/2)^2), h the atom spacing: it takes
//          the outer wall within h/2 of the middle section and the inner wall over a wider band (a
//          sphere on a ring); the vessel's grab: the atoms within the mid-wall's band half-width
//          sqrt(R^2 - r^2) (3 atoms: the grabbed segments' frames held, as the FEM's rigid ring).
//   force  a constant lateral force on the same sphere (FEM: shared by the nodes in it; vessel: by the
//          atoms in the vessel grab's sphere).
//
// Errors (mm, at the last frame), on displacements sampled at the vessel model's points:
//   centerline  each atom's displacement against the FEM ring at that atom (the centroid of its nodes);
//   surface     each drawn surface vertex's displacement (the vessel's rings are at the mid-wall radius)
//               against the FEM's, interpolated at the vertex's rest position in that ring (bilinear in
//               layer and sector).
// Near: atoms (and their rings) within 20 mm of arc length of the grab; far: the others. The reference
// is the Neo-Hookean FEM on quadratic tets on the coarsest mesh; every configuration (the vessel and
// the other FEM runs) is measured against it.
//
// Time: FEM static, per frame after the first (each a warm-started Newton solve; the first frame also
// captures the grab and factorises); setup = engine build + first frame. Vessel: wall time per 1/60 s
// step (one step per frame), and to rest.
//
//   vessel_vs_fem --out DIR [--centerline FILE] [--cases aorta,tube] [--levels 3] [--smooth 10]
//
// Outputs in DIR: vessel_vs_fem.md (the tables, also on stdout), vessel_vs_fem.csv, <case>/ inputs.
#include "ctsurg/core/centerline_file.h"
#include "ctsurg/core/error.h"
#include "ctsurg/core/tet_mesh_file.h"
#include "ctsurg/sim/scenario/scenario.h"
#include "ctsurg/sim/scenario/scenario_run.h"

#include <Eigen/Dense>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace ctsurg;
using namespace ctsurg::sim;
using V3 = Eigen::Vector3d;

namespace {

constexpr double kNearMm = 20;    // near the tool: within this arc length of the grab
constexpr double kPullMm = 15;    // the grab's displacement
constexpr double kMoveS = 0.25;   // over this time (15 frames of 1/60 s)
constexpr double kSettleS = 2.0;  // vessel: damped run after the motion

Provenance bench_provenance() { return {"vessel_vs_fem", "0", {}, {}, nlohmann::json::array()}; }

V3 at(const std::vector<double>& a, size_t i) { return {a[3 * i], a[3 * i + 1], a[3 * i + 2]}; }
V3 atf(const float* a, size_t i) { return {a[3 * i], a[3 * i + 1], a[3 * i + 2]}; }

// The vessel: atoms (n x 3, LPS mm) at even spacing, their mid-wall radius, the wall thickness.
struct Vessel {
  std::string name;
  std::vector<double> points, radius;
  double wall = 0;     // mm
  double spacing = 0;  // mm, between atoms
  size_t count() const { return radius.size(); }
};

// Resamples a polyline (n x 3, radius per point) to `n` points at even arc length.
void resample(std::vector<double>& p, std::vector<double>& r, size_t n) {
  const size_t m = r.size();
  std::vector<double> s(m, 0);
  for (size_t i = 1; i < m; ++i) s[i] = s[i - 1] + (at(p, i) - at(p, i - 1)).norm();
  std::vector<double> q, rq;
  size_t j = 0;
  for (size_t k = 0; k < n; ++k) {
    const double sk = s.back() * static_cast<double>(k) / static_cast<double>(n - 1);
    while (j + 2 < m && s[j + 1] < sk) ++j;
    const double u = std::clamp((sk - s[j]) / std::max(s[j + 1] - s[j], 1e-12), 0.0, 1.0);
    const V3 x = (1 - u) * at(p, j) + u * at(p, j + 1);
    q.insert(q.end(), {x[0], x[1], x[2]});
    rq.push_back((1 - u) * r[j] + u * r[j + 1]);
  }
  p = std::move(q);
  r = std::move(rq);
}

Vessel vessel_of_centerline(const fs::path& file, int smooth, double wall) {
  const Centerline c = read_centerline_file(file);
  if (c.branch_count() != 1) throw InputError(file.string(), "/centerline", "one branch expected, got " + std::to_string(c.branch_count()));
  Vessel v;
  v.name = "aorta";
  v.wall = wall;
  for (int64_t i = c.branch_offsets[0]; i < c.branch_offsets[1]; ++i) {
    for (int k = 0; k < 3; ++k) v.points.push_back(c.points[3 * static_cast<size_t>(i) + k]);
    v.radius.push_back(c.radius[static_cast<size_t>(i)]);
  }
  const size_t n = v.count();
  for (int it = 0; it < smooth; ++it) {  // Laplacian, ends kept
    std::vector<double> p = v.points, r = v.radius;
    for (size_t i = 1; i + 1 < n; ++i) {
      const V3 x = 0.5 * at(v.points, i) + 0.25 * (at(v.points, i - 1) + at(v.points, i + 1));
      for (int k = 0; k < 3; ++k) p[3 * i + k] = x[k];
      r[i] = 0.5 * v.radius[i] + 0.25 * (v.radius[i - 1] + v.radius[i + 1]);
    }
    v.points = std::move(p), v.radius = std::move(r);
  }
  resample(v.points, v.radius, n);
  v.spacing = (at(v.points, 1) - at(v.points, 0)).norm();
  return v;
}

Vessel straight_tube(double length, double radius, double wall, double spacing) {
  Vessel v;
  v.name = "tube";
  v.wall = wall;
  const size_t n = static_cast<size_t>(std::lround(length / spacing)) + 1;
  v.spacing = length / static_cast<double>(n - 1);
  for (size_t i = 0; i < n; ++i) {
    v.points.insert(v.points.end(), {0.0, 0.0, v.spacing * static_cast<double>(i)});
    v.radius.push_back(radius);
  }
  return v;
}

void write_centerline(const Vessel& v, const fs::path& path) {
  Centerline c;
  c.points = v.points;
  c.radius = v.radius;
  c.branch_offsets = {0, static_cast<int64_t>(v.count())};
  c.branch_nodes = {0, 1};
  const V3 a = at(v.points, 0), b = at(v.points, v.count() - 1);
  c.nodes = {a[0], a[1], a[2], b[0], b[1], b[2]};
  c.label = 1;
  c.parameters = "{}";
  write_centerline_file(path, c, bench_provenance());
}

// The FEM wall mesh and where its rings are.
struct WallMesh {
  int layers = 0, sectors = 0, per_atom = 0;
  TetMesh mesh;
  std::vector<V3> centre, n1, n2;  // per ring: the curve point and the rotation-minimising frame (n1 x n2 = tangent)
  std::vector<double> rho;         // per ring x (layers + 1): the layer radii
  size_t ring_of_atom(size_t a) const { return a * static_cast<size_t>(per_atom); }
  int32_t node(size_t ring, int layer, int sector) const {
    return static_cast<int32_t>((ring * static_cast<size_t>(layers + 1) + static_cast<size_t>(layer)) * static_cast<size_t>(sectors) +
                                static_cast<size_t>((sector % sectors + sectors) % sectors));
  }
};

WallMesh wall_mesh(const Vessel& v, int layers, int sectors, int per_atom) {
  WallMesh w;
  w.layers = layers, w.sectors = sectors, w.per_atom = per_atom;
  const size_t n = v.count();
  const auto P = [&](long i) {  // with mirrored ghosts at the ends
    if (i < 0) return V3(2 * at(v.points, 0) - at(v.points, 1));
    if (i >= static_cast<long>(n)) return V3(2 * at(v.points, n - 1) - at(v.points, n - 2));
    return at(v.points, static_cast<size_t>(i));
  };
  std::vector<V3> tangent;
  std::vector<double> radius;
  for (size_t i = 0; i + 1 < n; ++i)
    for (int k = 0; k < per_atom + (i + 2 == n ? 1 : 0); ++k) {
      const double u = static_cast<double>(k) / per_atom;
      const long j = static_cast<long>(i);
      const V3 p0 = P(j - 1), p1 = P(j), p2 = P(j + 1), p3 = P(j + 2);
      // Uniform Catmull-Rom and its derivative.
      const V3 x = 0.5 * (2 * p1 + (p2 - p0) * u + (2 * p0 - 5 * p1 + 4 * p2 - p3) * u * u + (3 * p1 - p0 - 3 * p2 + p3) * u * u * u);
      const V3 d = 0.5 * ((p2 - p0) + 2 * (2 * p0 - 5 * p1 + 4 * p2 - p3) * u + 3 * (3 * p1 - p0 - 3 * p2 + p3) * u * u);
      w.centre.push_back(x);
      tangent.push_back(d.normalized());
      radius.push_back((1 - u) * v.radius[i] + u * v.radius[i + 1]);
    }
  const size_t rings = w.centre.size();
  // Rotation-minimising frames by double reflection from a normal of the first tangent.
  V3 r0 = tangent[0].unitOrthogonal();
  for (size_t c = 0; c < rings; ++c) {
    if (c > 0) {
      const V3 v1 = w.centre[c] - w.centre[c - 1];
      const double c1 = v1.squaredNorm();
      const V3 rl = r0 - (2 / c1) * v1.dot(r0) * v1, tl = tangent[c - 1] - (2 / c1) * v1.dot(tangent[c - 1]) * v1;
      const V3 v2 = tangent[c] - tl;
      const double c2 = v2.squaredNorm();
      r0 = c2 > 1e-20 ? V3(rl - (2 / c2) * v2.dot(rl) * v2) : rl;
      r0 = (r0 - r0.dot(tangent[c]) * tangent[c]).normalized();
    }
    w.n1.push_back(r0);
    w.n2.push_back(tangent[c].cross(r0));
  }
  TetMesh& m = w.mesh;
  for (size_t c = 0; c < rings; ++c)
    for (int a = 0; a <= layers; ++a) {
      const double rho = radius[c] - v.wall / 2 + v.wall * a / layers;
      w.rho.push_back(rho);
      for (int b = 0; b < sectors; ++b) {
        const double th = 2 * M_PI * b / sectors;
        const V3 x = w.centre[c] + rho * (std::cos(th) * w.n1[c] + std::sin(th) * w.n2[c]);
        m.nodes.insert(m.nodes.end(), {x[0], x[1], x[2]});
      }
    }
  // Kuhn split of every (layer, sector, ring) cell: axes (radial, circumferential, axial) are right-handed.
  static const int perms[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {2, 1, 0}, {1, 0, 2}};
  const size_t last_held = rings - 1 - static_cast<size_t>(per_atom);
  for (size_t c = 0; c + 1 < rings; ++c)
    for (int b = 0; b < sectors; ++b)
      for (int a = 0; a < layers; ++a)
        for (int p = 0; p < 6; ++p) {
          int d[3] = {0, 0, 0};
          int32_t t[4];
          t[0] = w.node(c, a, b);
          for (int s = 0; s < 3; ++s) {
            d[perms[p][s]] = 1;
            t[s + 1] = w.node(c + static_cast<size_t>(d[2]), a + d[0], b + d[1]);
          }
          if (p >= 3) std::swap(t[2], t[3]);
          const V3 x0 = at(m.nodes, static_cast<size_t>(t[0]));
          const double vol = (at(m.nodes, static_cast<size_t>(t[1])) - x0)
                                 .dot((at(m.nodes, static_cast<size_t>(t[2])) - x0).cross(at(m.nodes, static_cast<size_t>(t[3])) - x0));
          if (!(vol > 0)) throw RuntimeError("vessel_vs_fem: " + v.name + ": tet with volume " + std::to_string(vol / 6) + " mm^3 at ring " +
                                             std::to_string(c) + " (the curve bends tighter than the outer radius: smooth more)");
          m.tets.insert(m.tets.end(), t, t + 4);
          m.tet_labels.push_back(c < static_cast<size_t>(per_atom) || c >= last_held ? 2 : 1);
        }
  m.quality.radius_edge_bin_edges = {0, 1};
  m.quality.radius_edge_histogram = {static_cast<int64_t>(m.tet_labels.size())};
  return w;
}

// A run's displacements sampled at the vessel model's points: per atom (n x 3) and per drawn surface
// vertex (#V x 3).
struct Sampled {
  std::vector<double> atoms, surface;
};

struct Error {
  double rms = 0, max = 0;
};

Error error_of(const std::vector<double>& a, const std::vector<double>& b, const std::vector<uint8_t>& use) {
  Error e;
  double sum = 0;
  int64_t n = 0;
  for (size_t i = 0; i < use.size(); ++i) {
    if (!use[i]) continue;
    const double d = (at(a, i) - at(b, i)).norm();
    sum += d * d, ++n, e.max = std::max(e.max, d);
  }
  e.rms = std::sqrt(sum / static_cast<double>(std::max<int64_t>(n, 1)));
  return e;
}

struct Case {
  Vessel v;
  fs::path dir;
  std::string load;  // pull | force
  double force_n = 0;
  V3 direction;      // unit, perpendicular to the axis at the grab
  size_t grab_atom = 0;
  double fem_radius = 0, vessel_radius = 0;  // grab spheres, mm
  std::vector<float> vessel_rest_surface;    // the vessel's rest surface (filled by its run)
  int spokes = 24;
};

struct Config {
  std::string model;  // vessel | fem
  std::string law;    // fem: linear | neo_hookean
  int order = 1;
  int level = 0;      // fem: index into the levels
};

struct Result {
  Config config;
  std::string label;
  int64_t nodes = 0, tets = 0, captured = 0;
  double setup = 0, frame = 0, total = 0;
  double unsettled = 0;  // vessel: the largest atom motion over the last 0.1 s, mm
  Sampled u;
  bool ok = false;
  std::string failure;
};

std::string tool_text(const Case& k, double radius) {
  const V3 c = at(k.v.points, k.grab_atom);
  std::ostringstream s;
  s.precision(10);
  s << "tools:\n";
  if (k.load == "pull") {
    const V3 d = kPullMm * k.direction;
    s << "  - grab:\n      radius_mm: " << radius << "\n      path:\n        - {t: 0, position_mm: [" << c[0] << ", " << c[1] << ", " << c[2]
      << "]}\n        - {t: " << kMoveS << ", offset_mm: [" << d[0] << ", " << d[1] << ", " << d[2] << "]}\n";
  } else {
    const V3 f = k.force_n * k.direction;
    s << "  - force:\n      radius_mm: " << radius << "\n      force_n: [" << f[0] << ", " << f[1] << ", " << f[2]
      << "]\n      path:\n        - {t: 0, position_mm: [" << c[0] << ", " << c[1] << ", " << c[2] << "]}\n";
  }
  return s.str();
}

const char* kMaterial = "material:\n  youngs_modulus_pa: 1.0e6\n  poisson_ratio: 0.45\n  density_g_per_cm3: 1.06\n";

std::string vessel_scenario(const Case& k) {
  std::ostringstream s;
  s.precision(10);
  s << "ctsurg_scenario: 1\nmodel:\n  kind: vessel\n  centerline: centerline.h5\nvessel:\n  wall_thickness_mm: " << k.v.wall
    << "\n  spokes: " << k.spokes << "\n  skinning: rmf\n"
    << kMaterial << "  damping_per_s: 30\nfixed:\n";
  const size_t n = k.v.count();
  for (const size_t a : {size_t(0), size_t(1), n - 2, n - 1}) {
    const V3 p = at(k.v.points, a);
    s << "  - box: {min: [" << p[0] - 0.1 << ", " << p[1] - 0.1 << ", " << p[2] - 0.1 << "], max: [" << p[0] + 0.1 << ", " << p[1] + 0.1
      << ", " << p[2] + 0.1 << "]}\n";
  }
  s << tool_text(k, k.vessel_radius) << "time:\n  duration_s: " << (k.load == "pull" ? kMoveS : 0.0) + kSettleS
    << "\n  dt_s: " << 1.0 / 60 << "\noutput:\n  trajectory: unused.h5\n  frame_interval_s: " << 1.0 / 60 << "\n  particles: true\n";
  return s.str();
}

std::string fem_scenario(const Case& k, const Config& c, const std::string& tetmesh) {
  std::ostringstream s;
  s << "ctsurg_scenario: 1\nmodel:\n  kind: fem\n  tetmesh: " << tetmesh << "\n  solver: static\n";
  if (c.order == 2) s << "  elements: quadratic\n";
  s << kMaterial << "  law: " << c.law << "\nfixed:\n  - label: 2\n" << tool_text(k, k.fem_radius);
  const double frame = 1.0 / 60, duration = (k.load == "pull" ? kMoveS : 0.0) + frame;  // the last frame at full load
  s << "time:\n  duration_s: " << duration << "\noutput:\n  trajectory: unused.h5\n  frame_interval_s: " << frame << "\n";
  return s.str();
}

// The rest points (#P x 3, LPS mm) inside the tool's sphere at the grab atom: what the tool holds.
int64_t inside(const Case& k, const std::vector<float>& rest, double radius) {
  const V3 c = at(k.v.points, k.grab_atom);
  int64_t n = 0;
  for (size_t i = 0; i < rest.size() / 3; ++i) n += (atf(rest.data(), i) - c).norm() <= radius;
  return n;
}

Result run_vessel(Case& k) {
  Result r;
  r.config = {"vessel", "", 1, 0};
  r.label = "vessel model (" + std::to_string(k.v.count()) + " atoms, dt 1/60 s)";
  std::cerr << k.v.name << " " << k.load << ": " << r.label << " ... " << std::flush;
  try {
    const Scenario s = parse_scenario(vessel_scenario(k), k.dir / "vessel.yaml", k.dir);
    RunReport rep;
    const Trajectory t = run_scenario(s, &rep);
    r.nodes = rep.particles;
    r.captured = inside(k, t.rest_particles, k.vessel_radius);
    r.setup = rep.setup_s;
    r.total = rep.wall_s;
    r.frame = rep.wall_s / static_cast<double>(std::max<int64_t>(rep.steps, 1));
    if (rep.fixed != 4) throw RuntimeError("vessel: " + std::to_string(rep.fixed) + " atoms fixed, 4 expected");
    const int64_t f = t.frame_count() - 1, g = std::max<int64_t>(0, f - 6);
    const size_t na = k.v.count(), nv = static_cast<size_t>(t.vertex_count());
    const float* P = t.particles.data();
    for (size_t a = 0; a < na; ++a) {
      const V3 u = atf(P + f * static_cast<int64_t>(3 * na), a) - atf(t.rest_particles.data(), a);
      r.u.atoms.insert(r.u.atoms.end(), {u[0], u[1], u[2]});
      r.unsettled = std::max(r.unsettled, (atf(P + f * static_cast<int64_t>(3 * na), a) - atf(P + g * static_cast<int64_t>(3 * na), a)).norm());
    }
    for (size_t i = 0; i < nv; ++i) {
      const V3 u = atf(t.frame_vertices(f), i) - atf(t.rest_vertices.data(), i);
      r.u.surface.insert(r.u.surface.end(), {u[0], u[1], u[2]});
    }
    k.vessel_rest_surface = t.rest_vertices;
    k.spokes = static_cast<int>(nv / na);
    r.ok = true;
    std::cerr << r.frame * 1e3 << " ms/step, settled to " << r.unsettled << " mm over the last 0.1 s\n";
  } catch (const std::exception& e) {
    r.failure = e.what();
    std::cerr << "failed: " << r.failure << "\n";
  }
  return r;
}

Result run_fem(const Case& k, const Config& c, const WallMesh& w, const std::string& tetmesh) {
  Result r;
  r.config = c;
  r.label = std::string("FEM ") + (c.law == "neo_hookean" ? "Neo-Hookean" : "linear") + (c.order == 2 ? " P2" : " P1") + " " +
            std::to_string(w.layers) + "x" + std::to_string(w.sectors) + "x" + std::to_string(w.centre.size() - 1);
  std::cerr << k.v.name << " " << k.load << ": " << r.label << " ... " << std::flush;
  try {
    const Scenario s = parse_scenario(fem_scenario(k, c, tetmesh), k.dir / "fem.yaml", k.dir);
    RunReport rep;
    const Trajectory t = run_scenario(s, &rep);
    r.nodes = rep.particles;
    r.tets = rep.elements;
    r.captured = inside(k, t.rest_vertices, k.fem_radius);
    const auto& fw = rep.frame_wall_s;
    const int64_t frames = t.frame_count();
    r.total = rep.setup_s + rep.wall_s;
    if (frames > 2) {
      r.setup = rep.setup_s + fw[1];
      r.frame = (fw.back() - fw[1]) / static_cast<double>(frames - 2);
    } else {
      r.setup = rep.setup_s;
      r.frame = rep.wall_s;
    }
    // The vertices are the nodes (no surface): the first #N are the linear mesh's (a quadratic model
    // adds its edge nodes after them).
    const int64_t f = frames - 1;
    const float* X = t.frame_vertices(f);
    const float* X0 = t.rest_vertices.data();
    const auto disp = [&](int32_t i) { return V3(atf(X, static_cast<size_t>(i)) - atf(X0, static_cast<size_t>(i))); };
    const size_t na = k.v.count();
    const int L = w.layers, S = w.sectors;
    for (size_t a = 0; a < na; ++a) {
      const size_t ring = w.ring_of_atom(a);
      V3 u = V3::Zero();
      for (int l = 0; l <= L; ++l)
        for (int b = 0; b < S; ++b) u += disp(w.node(ring, l, b));
      u /= (L + 1) * S;
      r.u.atoms.insert(r.u.atoms.end(), {u[0], u[1], u[2]});
    }
    const size_t nv = k.vessel_rest_surface.size() / 3, spokes = nv / na;
    for (size_t i = 0; i < nv; ++i) {
      const size_t ring = w.ring_of_atom(i / spokes);
      const V3 d = atf(k.vessel_rest_surface.data(), i) - w.centre[ring];
      const double x = d.dot(w.n1[ring]), y = d.dot(w.n2[ring]), rad = std::hypot(x, y);
      double th = std::atan2(y, x) / (2 * M_PI) * S;
      if (th < 0) th += S;
      const int b0 = static_cast<int>(std::floor(th));
      const double fb = th - b0;
      const double* rho = &w.rho[ring * static_cast<size_t>(L + 1)];
      const double fl = std::clamp((rad - rho[0]) / (rho[L] - rho[0]) * L, 0.0, static_cast<double>(L));
      const int l0 = std::min(static_cast<int>(std::floor(fl)), L - 1);
      const double fr = fl - l0;
      const V3 u = (1 - fr) * ((1 - fb) * disp(w.node(ring, l0, b0)) + fb * disp(w.node(ring, l0, b0 + 1))) +
                   fr * ((1 - fb) * disp(w.node(ring, l0 + 1, b0)) + fb * disp(w.node(ring, l0 + 1, b0 + 1)));
      r.u.surface.insert(r.u.surface.end(), {u[0], u[1], u[2]});
    }
    r.ok = true;
    std::cerr << "setup " << r.setup << " s, " << r.frame << " s/frame, " << r.captured << " nodes grabbed\n";
  } catch (const std::exception& e) {
    r.failure = e.what();
    std::cerr << "failed: " << r.failure << "\n";
  }
  return r;
}

std::string csv_text(std::string t) {
  for (char& ch : t)
    if (ch == ',' || ch == '"' || ch == '\n' || ch == '\r') ch = ch == ',' ? ';' : ' ';
  return t;
}

}  // namespace

int main(int argc, char** argv) {
  fs::path out, centerline;
  std::string cases = "aorta,tube", loads = "pull,force";
  int max_levels = 3, smooth = 10;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--out" && i + 1 < argc) out = argv[++i];
    else if (a == "--centerline" && i + 1 < argc) centerline = argv[++i];
    else if (a == "--cases" && i + 1 < argc) cases = argv[++i];
    else if (a == "--loads" && i + 1 < argc) loads = argv[++i];
    else if (a == "--levels" && i + 1 < argc) max_levels = std::atoi(argv[++i]);
    else if (a == "--smooth" && i + 1 < argc) smooth = std::atoi(argv[++i]);
    else {
      std::cerr << "usage: vessel_vs_fem --out DIR [--centerline FILE] [--cases aorta,tube] [--loads pull,force] [--levels 1-3] [--smooth N]\n";
      return 2;
    }
  }
  if (out.empty() || (cases.find("aorta") != std::string::npos && centerline.empty())) {
    std::cerr << "vessel_vs_fem: --out is required, and --centerline for the aorta\n";
    return 2;
  }
  try {
    fs::create_directories(out);
    std::vector<Vessel> vessels;
    if (cases.find("aorta") != std::string::npos) vessels.push_back(vessel_of_centerline(centerline, smooth, 2.0));
    if (cases.find("tube") != std::string::npos) vessels.push_back(straight_tube(80, 5, 1, 2));
    // Levels: (radial layers, sectors); rings per atom spacing so that the axial size is about the
    // circumferential one at the mid-wall.
    const std::vector<std::pair<int, int>> levels{{2, 24}, {3, 36}, {4, 48}};
    std::ofstream csv(out / "vessel_vs_fem.csv");
    csv << "case,load,configuration,nodes,tets,grabbed,setup_s,frame_s,total_s,centerline_near_rms_mm,centerline_near_max_mm,"
           "centerline_far_rms_mm,centerline_far_max_mm,surface_near_rms_mm,surface_near_max_mm,surface_far_rms_mm,surface_far_max_mm,"
           "unsettled_mm,status\n";
    std::ostringstream md;
    md << "Vessel model against full FEM of the same vessel (bench/vessel_vs_fem.cpp). E 1 MPa, nu 0.45. Errors: displacement at the "
          "last frame against the reference (the first row: Neo-Hookean on quadratic tets on the coarsest mesh), mm, RMS / max; near: "
          "within " << kNearMm << " mm of arc length of the grab. FEM time: per static frame after the first; vessel: per 1/60 s step.\n";
    for (const Vessel& v : vessels) {
      const double mid = v.radius[v.count() / 2];
      double rmin = 1e9, rmax = 0;
      for (const double r : v.radius) rmin = std::min(rmin, r), rmax = std::max(rmax, r);
      for (const std::string load : {"pull", "force"}) {
        if (loads.find(load) == std::string::npos) continue;
        Case k;
        k.v = v;
        k.load = load;
        k.dir = out / v.name;
        fs::create_directories(k.dir);
        write_centerline(v, k.dir / "centerline.h5");
        k.grab_atom = v.count() / 2;
        const V3 tan = (at(v.points, k.grab_atom + 1) - at(v.points, k.grab_atom - 1)).normalized();
        const V3 ant(0, -1, 0);  // LPS: anterior is -y
        k.direction = (ant - ant.dot(tan) * tan).normalized();
        const double rout = mid + v.wall / 2;
        k.fem_radius = std::sqrt(rout * rout + 0.25 * v.spacing * v.spacing);
        k.vessel_radius = std::sqrt(k.fem_radius * k.fem_radius - mid * mid);
        // The force: about what bends the held span by a fifth of its radius (clamped-clamped beam,
        // F L^3 / (192 E I)), rounded.
        {
          const double ro = rout, ri = mid - v.wall / 2, I = M_PI / 4 * (std::pow(ro, 4) - std::pow(ri, 4));
          const double L = v.spacing * static_cast<double>(v.count() - 3);
          const double F = 0.2 * mid * 192 * 1e6 * I / (L * L * L) * 1e-6;  // N
          const double p = std::pow(10, std::floor(std::log10(F)));
          k.force_n = std::round(F / p) * p;
        }
        std::vector<Result> results;
        Result ves = run_vessel(k);
        if (!ves.ok) throw RuntimeError("vessel run failed: " + ves.failure);
        std::vector<WallMesh> meshes;
        for (int li = 0; li < std::min<int>(max_levels, static_cast<int>(levels.size())); ++li) {
          const auto [layers, sectors] = levels[static_cast<size_t>(li)];
          const double hc = 2 * M_PI * mid / sectors;
          const int per_atom = std::max(1, static_cast<int>(std::lround(v.spacing / hc)));
          meshes.push_back(wall_mesh(v, layers, sectors, per_atom));
          write_tet_mesh_file(k.dir / ("wall_" + std::to_string(li) + ".h5"), meshes.back().mesh, bench_provenance());
        }
        // The reference first: Neo-Hookean on quadratic tets on the coarsest mesh (finer ones take
        // minutes a frame on 2 cores); its own discretisation error shows against the P1 levels.
        const int ref_level = 0;
        std::vector<Config> configs{{"fem", "neo_hookean", 2, ref_level}};
        for (int li = 0; li < static_cast<int>(meshes.size()); ++li) {
          configs.push_back({"fem", "neo_hookean", 1, li});
          configs.push_back({"fem", "linear", 1, li});
        }
        if (ref_level > 0) configs.push_back({"fem", "neo_hookean", 2, 0});
        configs.push_back({"fem", "linear", 2, ref_level});
        for (const Config& c : configs)
          results.push_back(run_fem(k, c, meshes[static_cast<size_t>(c.level)], "wall_" + std::to_string(c.level) + ".h5"));
        results.push_back(ves);
        const Result& ref = results.front();
        if (!ref.ok) throw RuntimeError("reference FEM failed: " + ref.failure);
        // Near and far, by atom (a surface vertex goes with its ring's atom).
        const size_t na = v.count(), nv = ves.u.surface.size() / 3, spokes = nv / na;
        std::vector<uint8_t> an(na), af(na), sn(nv), sf(nv);
        for (size_t a = 0; a < na; ++a) {
          const bool near = std::abs(static_cast<double>(a) - static_cast<double>(k.grab_atom)) * v.spacing <= kNearMm;
          an[a] = near, af[a] = !near;
        }
        for (size_t i = 0; i < nv; ++i) sn[i] = an[i / spokes], sf[i] = af[i / spokes];
        double peak = 0;
        for (size_t a = 0; a < na; ++a) peak = std::max(peak, at(ref.u.atoms, a).norm());
        char head[1024];
        std::snprintf(head, sizeof head,
                      "\n#### %s, %s (%zu atoms %.2f mm apart, r %.1f-%.1f mm, wall %.1f mm; %s; reference's largest centerline "
                      "displacement %.2f mm)\n\nGrab spheres: FEM %.2f mm (on the axis at atom %zu), vessel %.2f mm.\n\n",
                      v.name.c_str(), load.c_str(), na, v.spacing, rmin, rmax, v.wall,
                      load == "pull" ? "the middle pulled 15 mm anterior" : ("a " + std::to_string(k.force_n).substr(0, 5) + " N anterior force").c_str(),
                      peak, k.fem_radius, k.grab_atom, k.vessel_radius);
        md << head
           << "| configuration | nodes (tets) | held by the tool | setup | time per frame | centerline near | centerline far | surface near | "
              "surface far |\n|---|---:|---:|---:|---:|---|---|---|---|\n";
        for (const Result& r : results) {
          char buf[1024];
          if (!r.ok) {
            std::snprintf(buf, sizeof buf, "| %s | failed: %s | | | | | | | |\n", r.label.c_str(), csv_text(r.failure).c_str());
            md << buf;
            csv << v.name << "," << load << "," << r.label << ",,,,,,,,,,,,,,,,failed: " << csv_text(r.failure) << "\n";
            continue;
          }
          const Error cn = error_of(r.u.atoms, ref.u.atoms, an), cf = error_of(r.u.atoms, ref.u.atoms, af);
          const Error snr = error_of(r.u.surface, ref.u.surface, sn), sfr = error_of(r.u.surface, ref.u.surface, sf);
          const std::string nodes = std::to_string(r.nodes) + (r.tets ? " (" + std::to_string(r.tets) + ")" : "");
          std::snprintf(buf, sizeof buf, "| %s%s | %s | %lld | %.3g s | %.3g ms | %.2f / %.2f | %.2f / %.2f | %.2f / %.2f | %.2f / %.2f |\n",
                        r.label.c_str(), &r == &ref ? " (reference)" : "", nodes.c_str(), static_cast<long long>(r.captured), r.setup,
                        r.frame * 1e3, cn.rms, cn.max, cf.rms, cf.max, snr.rms, snr.max, sfr.rms, sfr.max);
          md << buf;
          csv << v.name << "," << load << "," << r.label << "," << r.nodes << "," << r.tets << "," << r.captured << "," << r.setup << ","
              << r.frame << "," << r.total << "," << cn.rms << "," << cn.max << "," << cf.rms << "," << cf.max << "," << snr.rms << ","
              << snr.max << "," << sfr.rms << "," << sfr.max << "," << r.unsettled << ",ok\n";
        }
        csv.flush();
        std::snprintf(head, sizeof head, "\nThe vessel run's largest atom motion over its last 0.1 s: %.2g mm (at rest).\n", ves.unsettled);
        md << head;
      }
    }
    std::cout << md.str();
    std::ofstream(out / "vessel_vs_fem.md") << md.str();
  } catch (const std::exception& e) {
    std::cerr << "vessel_vs_fem: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
