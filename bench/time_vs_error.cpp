// Time against error (issues 9 and 16): the same physical scenario run with every model and setting a
// user can pick (implicit-grid springs, explicit springs from the tet mesh; linear, corotational, StVK
// and Neo-Hookean FEM on linear or quadratic tets, static with the solver's tolerance in mm, implicit
// and explicit dynamics; several grid and mesh resolutions, two time-step safety factors), each timed
// and compared with a reference:
//
//   cantilever  a 40 x 8 x 8 mm bar clamped at x = 0, a 1 mN tip force (-z); reference: Neo-Hookean
//               static on quadratic tets at the finest level (and Euler-Bernoulli, w(x) = F x^2 (3L - x) /
//               (6 E I), u_x = -(z - zc) w'(x), in runs.csv);
//   kidney      the right kidney of the upper-abdomen sample, posterior fifth fixed, a point force on
//               the anterior surface (the FEM paper's experiment); reference: Neo-Hookean static on
//               quadratic tets (levels: one folder per resolution, made by bench/time_vs_error.sh);
//   heart       the bundled heart, base fixed, apex grabbed and pulled 14.4 mm over 15 frames of 1/60 s
//               (a live drag), held; reference as the kidney's.
// The reference's own error is estimated from the same model one level coarser (Richardson:
// |u_h' - u_h| / ((h'/h)^p - 1), p = 2 and 3) and stated with the tables.
//
// Error: the displacement of the reference's rest surface vertices (the finest level's marching-cubes
// surface), each run's displacement carried there from its own surface by inverse-distance weights of
// the 4 nearest rest vertices; RMS and max over the vertices, mm, at the last frame.
//
// Time: setup (RunReport::setup_s: files, model, factorisations in the engine; for static runs also the
// first frame, whose grab capture analyses and factorises the new constraint set) apart from the time
// per frame: static runs, the mean over the frames after the first (each a warm-started Newton solve);
// dynamic runs (springs, explicit and implicit FEM), the loop's wall time per 1/60 s simulated. The
// heart's budgets are by time per frame; the cantilever's and kidney's (one load) by setup + loop.
//
// Outputs in OUT: runs.csv (one row per configuration), curves.csv (dynamic runs: error per frame),
// pareto_<scenario>.png (time against final RMS error, log-log, one mark per configuration, the Pareto
// front joined; the reference is not a configuration), budgets.md (per scenario and error budget, the
// fastest configuration within it), reference_<scenario>.bin (the cached reference displacements).
//
//   time_vs_error --inputs DIR --out DIR [--scenarios cantilever,kidney,heart] [--quick]
//
// DIR holds kidney/v<h>/ and heart/v<h>/ folders with grid.h5, surface.h5, tetmesh.h5 (made by the .sh);
// the cantilever's inputs are generated here.
#include "ctsurg/core/error.h"
#include "ctsurg/core/occupancy_grid_file.h"
#include "ctsurg/core/surface_mesh_file.h"
#include "ctsurg/core/tet_mesh_file.h"
#include "ctsurg/core/volume.h"
#include "ctsurg/mesh/lattice_padding.h"
#include "ctsurg/mesh/marching_cubes.h"
#include "ctsurg/sim/fem/fem_box_mesh.h"
#include "ctsurg/sim/scenario/scenario.h"
#include "ctsurg/sim/scenario/scenario_run.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace ctsurg;
using namespace ctsurg::sim;

namespace {

constexpr double kNearMm = 20;  // the local-region table's "near the tool": within this of the most displaced vertex

struct Level {
  double h = 0;  // mm, grid cell and tet size
  fs::path dir;  // grid.h5, surface.h5, tetmesh.h5 (and surface_fem.h5 for the cantilever)
};

struct Spec {
  std::string name;
  std::vector<Level> levels;  // coarse to fine
  size_t reference_level = 0; // the quadratic Neo-Hookean reference's level (its error: the level before)
  std::string material, fixed;
  std::string tools;          // the load: for the heart a grab moving over move_s, then held
  double move_s = 0;          // s, the tool's motion (0: a constant load)
  double settle_s = 0;        // s, dynamic runs: simulated after the motion
  double damping = 0;         // 1/s, mass-proportional (about twice the lowest mode's angular frequency)
  bool cantilever = false;
  bool per_frame = false;     // budgets by time per frame (a live session) instead of setup + loop
};

struct Config {
  std::string model;       // spring_grid | explicit_springs | fem
  std::string law;         // fem: linear | corotational | stvk | neo_hookean
  std::string solver = "dynamic";  // fem: static | implicit | dynamic
  int order = 1;           // fem: 1 linear tets, 2 quadratic
  double tolerance_mm = 0; // fem static / implicit: the solver's stopping rule (0: its default)
  std::string linear;      // fem static: "" (auto) | iterative
  double safety = 0.5;     // springs and explicit FEM
  const Level* level = nullptr;
  double local_mm = 0;     // fem static: local_region radius (fem_local_region.h); 0: the whole mesh
  int balance = 0;         // local_region balance_iterations
  bool dynamic() const { return model != "fem" || solver != "static"; }
  std::string family() const {  // the plot's colour
    if (model != "fem") return model;
    return law + (order == 2 ? " P2" : "") + (solver == "static" ? "" : " " + solver) + (local_mm > 0 ? " local" : "");
  }
  std::string label() const {
    std::ostringstream s;
    s << (model == "fem" ? "fem " + law + (order == 2 ? " P2" : "") + " " + solver : model) << " h" << level->h;
    if (tolerance_mm > 0) s << " tol" << tolerance_mm;
    if (!linear.empty()) s << " " << linear;
    if (local_mm > 0) s << " local R" << local_mm << (balance > 0 ? " balanced" : "");
    if (model != "fem" || solver == "dynamic") s << " sf" << safety;
    return s.str();
  }
};

Provenance bench_provenance() { return {"time_vs_error", "0", {}, {}, nlohmann::json::array()}; }

// The cantilever's inputs at cell size h: an occupancy block of x in [-h, 40] (the first layer, x < 0,
// is fixed: the clamp), y, z in [0, 8], its surface; the surface of x in [0, 40] for the tet models;
// a Kuhn tet mesh of [0, 40] x [0, 8] x [0, 8].
void write_cantilever(const Level& l) {
  fs::create_directories(l.dir);
  const int n = static_cast<int>(std::lround(8 / l.h)), nx = static_cast<int>(std::lround(40 / l.h));
  for (int stub = 1; stub >= 0; --stub) {
    ImageGeometry g;
    g.dims = {nx + stub + 2, n + 2, n + 2};
    g.spacing = Eigen::Vector3d(l.h, l.h, l.h);
    g.origin = Eigen::Vector3d(-stub * l.h - 0.5 * l.h, -0.5 * l.h, -0.5 * l.h);
    OccupancyGrid grid;
    grid.occupancy = Volume<uint8_t>(g, 0);
    for (int k = 1; k <= n; ++k)
      for (int j = 1; j <= n; ++j)
        for (int i = 1; i <= nx + stub; ++i) grid.occupancy(i, j, k) = 1;
    grid.fraction = Volume<float>(g, 0.f);
    grid.label = Volume<uint16_t>(g, 0);
    for (size_t i = 0; i < grid.occupancy.voxels.size(); ++i) {
      grid.fraction.voxels[i] = grid.occupancy.voxels[i] ? 1.f : 0.f;
      grid.label.voxels[i] = grid.occupancy.voxels[i];
    }
    grid.mask = grid.label;
    grid.label_names = {{1, "bar"}};
    const SurfaceMesh s = marching_cubes(pad_lattice(grid.fraction, 0.f, 1), 0.5);
    if (stub) {
      write_occupancy_grid_file(l.dir / "grid.h5", grid, bench_provenance());
      write_surface_mesh_file(l.dir / "surface.h5", s, bench_provenance());
    } else {
      write_surface_mesh_file(l.dir / "surface_fem.h5", s, bench_provenance());
    }
  }
  write_tet_mesh_file(l.dir / "tetmesh.h5", tet_mesh_of(fem_box_mesh({nx, n, n}, {40, 8, 8})), bench_provenance());
}

// single_frame: one output frame at the end (the reference: only the final equilibrium is compared).
std::string scenario_text(const Spec& sp, const Config& c, bool single_frame = false) {
  std::ostringstream s;
  s << "ctsurg_scenario: 1\nmodel:\n";
  if (c.model == "spring_grid") s << "  kind: spring_grid\n  grid: grid.h5\n  surface: surface.h5\n";
  if (c.model == "explicit_springs")
    s << "  kind: explicit_springs\n  springs_from: tetmesh\n  grid: grid.h5\n  tetmesh: tetmesh.h5\n  surface: "
      << (sp.cantilever ? "surface_fem.h5" : "surface.h5") << "\n";
  if (c.model == "fem") {
    s << "  kind: fem\n  tetmesh: tetmesh.h5\n  surface: " << (sp.cantilever ? "surface_fem.h5" : "surface.h5")
      << "\n  solver: " << c.solver << "\n";
    if (c.order == 2) s << "  elements: quadratic\n";
  }
  s << "material:\n" << (c.model == "fem" ? "  law: " + c.law + "\n" : "") << sp.material << "  damping_per_s: " << sp.damping << "\n" << sp.fixed << sp.tools;
  // Frames of 1/60 s while the tool moves (a quasi-static solve each); dynamic runs go on to settle.
  double frame = sp.move_s > 0 ? 1.0 / 60 : c.dynamic() ? sp.settle_s / 40 : 0.1;
  const double duration = c.dynamic() ? sp.move_s + sp.settle_s : std::max(sp.move_s, frame);
  if (single_frame) frame = duration;
  s << "time:\n  duration_s: " << duration << "\n";
  if (c.model != "fem" || c.solver == "dynamic") s << "  safety_factor: " << c.safety << "\n";
  s << "output:\n  trajectory: unused.h5\n  frame_interval_s: " << frame << "\n";
  if (c.model == "fem" && c.solver != "dynamic" && (c.tolerance_mm > 0 || !c.linear.empty() || c.local_mm > 0)) {
    s << "solver:\n";
    if (c.tolerance_mm > 0) s << "  tolerance_mm: " << c.tolerance_mm << "\n";
    if (!c.linear.empty()) s << "  linear: " << c.linear << "\n";
    if (c.local_mm > 0) s << "  local_region: {radius_mm: " << c.local_mm << ", balance_iterations: " << c.balance << "}\n";
  }
  return s.str();
}

// The 4 nearest rest vertices of `from` for every point of `to` and their inverse-distance weights.
struct Transfer {
  std::vector<int32_t> index;  // #to x 4
  std::vector<double> weight;  // #to x 4
};

Transfer make_transfer(const std::vector<float>& from, const std::vector<double>& to) {
  Transfer t;
  const size_t nf = from.size() / 3, nt = to.size() / 3;
  t.index.resize(4 * nt);
  t.weight.resize(4 * nt);
  // Uniform bucket grid over `from`.
  double lo[3] = {1e30, 1e30, 1e30}, hi[3] = {-1e30, -1e30, -1e30};
  for (size_t i = 0; i < nf; ++i)
    for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], double(from[3 * i + c])), hi[c] = std::max(hi[c], double(from[3 * i + c]));
  const double cell = 2.0;
  int dims[3];
  for (int c = 0; c < 3; ++c) dims[c] = std::max(1, static_cast<int>((hi[c] - lo[c]) / cell) + 1);
  auto key = [&](int a, int b, int d) { return (static_cast<int64_t>(d) * dims[1] + b) * dims[0] + a; };
  std::vector<std::vector<int32_t>> buckets(static_cast<size_t>(dims[0]) * dims[1] * dims[2]);
  auto coord = [&](double v, int c) { return std::clamp(static_cast<int>((v - lo[c]) / cell), 0, dims[c] - 1); };
  for (size_t i = 0; i < nf; ++i)
    buckets[static_cast<size_t>(key(coord(from[3 * i], 0), coord(from[3 * i + 1], 1), coord(from[3 * i + 2], 2)))].push_back(static_cast<int32_t>(i));
  for (size_t p = 0; p < nt; ++p) {
    std::array<std::pair<double, int32_t>, 4> best;
    best.fill({1e300, 0});
    const int ci[3] = {coord(to[3 * p], 0), coord(to[3 * p + 1], 1), coord(to[3 * p + 2], 2)};
    for (int r = 0;; ++r) {
      for (int d = ci[2] - r; d <= ci[2] + r; ++d)
        for (int b = ci[1] - r; b <= ci[1] + r; ++b)
          for (int a = ci[0] - r; a <= ci[0] + r; ++a) {
            if (std::max({std::abs(a - ci[0]), std::abs(b - ci[1]), std::abs(d - ci[2])}) != r) continue;
            if (a < 0 || b < 0 || d < 0 || a >= dims[0] || b >= dims[1] || d >= dims[2]) continue;
            for (const int32_t i : buckets[static_cast<size_t>(key(a, b, d))]) {
              double d2 = 0;
              for (int c = 0; c < 3; ++c) d2 += (from[3 * i + c] - to[3 * p + c]) * (from[3 * i + c] - to[3 * p + c]);
              if (d2 < best[3].first) {
                best[3] = {d2, i};
                std::sort(best.begin(), best.end());
              }
            }
          }
      // Every vertex within r cells is seen; stop when the 4th nearest is nearer than that.
      if (best[3].first < (r * cell) * (r * cell) || r > std::max({dims[0], dims[1], dims[2]})) break;
    }
    double sum = 0;
    for (int k = 0; k < 4; ++k) sum += 1 / (std::sqrt(best[k].first) + 1e-6);
    for (int k = 0; k < 4; ++k) {
      t.index[4 * p + k] = best[k].second;
      t.weight[4 * p + k] = 1 / (std::sqrt(best[k].first) + 1e-6) / sum;
    }
  }
  return t;
}

// Displacements (#to x 3) of the frame `f` of `traj` carried to the transfer's points.
std::vector<double> carried_displacement(const Trajectory& traj, int64_t f, const Transfer& t) {
  const float* x = traj.frame_vertices(f);
  std::vector<double> u(t.index.size() / 4 * 3, 0.0);
  for (size_t p = 0; p < t.index.size() / 4; ++p)
    for (int k = 0; k < 4; ++k) {
      const size_t i = static_cast<size_t>(t.index[4 * p + k]);
      for (int c = 0; c < 3; ++c) u[3 * p + c] += t.weight[4 * p + k] * (double(x[3 * i + c]) - traj.rest_vertices[3 * i + c]);
    }
  return u;
}

struct Error {
  double rms = 0, max = 0;
};
Error error_of(const std::vector<double>& u, const std::vector<double>& ref, const std::vector<uint8_t>& use) {
  Error e;
  double sum = 0;
  int64_t n = 0;
  for (size_t p = 0; p < ref.size() / 3; ++p) {
    if (!use[p]) continue;
    double d2 = 0;
    for (int c = 0; c < 3; ++c) d2 += (u[3 * p + c] - ref[3 * p + c]) * (u[3 * p + c] - ref[3 * p + c]);
    sum += d2, ++n;
    e.max = std::max(e.max, std::sqrt(d2));
  }
  e.rms = std::sqrt(sum / std::max<int64_t>(n, 1));
  return e;
}

struct Result {
  Config config;
  std::string label;
  int64_t nodes = 0;
  double dt = 0;
  double setup = 0;     // s: engine build (+ the first frame of a static run)
  double frame = 0;     // s: per frame after setup (see the header)
  double total = 0;     // s: engine build + loop
  int64_t steps = 0;
  Error err, analytic;
  double volume_change = 0;
  bool ok = false;
  std::string failure;
  std::vector<double> curve_wall, curve_rms, curve_max, curve_time;
  std::vector<double> final_u;  // the last frame's displacement at the reference points
  double cost(bool per_frame) const { return per_frame ? frame : total; }
};

// Pareto plot: wall time (x, log) against final RMS error (y, log), colour per model, front joined.
void pareto_png(const std::string& title, const std::vector<Result>& rs, bool per_frame, const fs::path& path) {
  const int W = 820, H = 520, L = 70, R = 230, T = 30, B = 50;
  cv::Mat img(H, W, CV_8UC3, cv::Scalar(255, 255, 255));
  double x0 = 1e30, x1 = 0, y0 = 1e30, y1 = 0;
  for (const auto& r : rs)
    if (r.ok)
      x0 = std::min(x0, std::max(r.cost(per_frame), 1e-5)), x1 = std::max(x1, r.cost(per_frame)), y0 = std::min(y0, std::max(r.err.rms, 1e-3)),
      y1 = std::max(y1, r.err.rms);
  x0 = std::pow(10, std::floor(std::log10(x0))), x1 = std::pow(10, std::ceil(std::log10(x1)));
  y0 = std::pow(10, std::floor(std::log10(y0))), y1 = std::pow(10, std::ceil(std::log10(y1)));
  auto px = [&](double x) { return L + (W - L - R) * (std::log10(std::max(x, 1e-5)) - std::log10(x0)) / (std::log10(x1) - std::log10(x0)); };
  auto py = [&](double y) { return H - B - (H - B - T) * (std::log10(std::max(y, 1e-3)) - std::log10(y0)) / (std::log10(y1) - std::log10(y0)); };
  const cv::Scalar black(0, 0, 0), grey(200, 200, 200);
  for (double x = x0; x <= x1 * 1.001; x *= 10) {
    cv::line(img, {int(px(x)), T}, {int(px(x)), H - B}, grey);
    std::ostringstream s;
    s << x;
    cv::putText(img, s.str(), {int(px(x)) - 12, H - B + 18}, cv::FONT_HERSHEY_SIMPLEX, 0.4, black);
  }
  for (double y = y0; y <= y1 * 1.001; y *= 10) {
    cv::line(img, {L, int(py(y))}, {W - R, int(py(y))}, grey);
    std::ostringstream s;
    s << y;
    cv::putText(img, s.str(), {8, int(py(y)) + 4}, cv::FONT_HERSHEY_SIMPLEX, 0.4, black);
  }
  cv::rectangle(img, {L, T}, {W - R, H - B}, black);
  cv::putText(img, per_frame ? "time per frame after setup, s" : "setup + solve time, s", {(W - R) / 2 - 60, H - 12},
              cv::FONT_HERSHEY_SIMPLEX, 0.45, black);
  cv::putText(img, "surface RMS error, mm", {8, 18}, cv::FONT_HERSHEY_SIMPLEX, 0.45, black);
  cv::putText(img, title, {L + 150, 18}, cv::FONT_HERSHEY_SIMPLEX, 0.5, black);
  // One colour per model family, in the order met.
  static const cv::Scalar palette[] = {{200, 80, 0},   {0, 160, 0},   {0, 140, 255}, {180, 0, 180}, {0, 0, 220},   {128, 128, 0},
                                       {0, 100, 100},  {255, 0, 255}, {90, 60, 30},  {0, 200, 200}, {120, 120, 255}, {60, 60, 60},
                                       {200, 160, 0},  {0, 90, 200},  {150, 220, 90}, {40, 40, 160}};
  std::vector<std::string> families;
  for (const auto& r : rs)
    if (r.ok && std::find(families.begin(), families.end(), r.config.family()) == families.end()) families.push_back(r.config.family());
  std::map<std::string, cv::Scalar> colour;
  for (size_t i = 0; i < families.size(); ++i) colour[families[i]] = palette[i % (sizeof palette / sizeof palette[0])];
  // Front: sorted by time, keep the points with an error below every faster one.
  std::vector<const Result*> ok;
  for (const auto& r : rs)
    if (r.ok) ok.push_back(&r);
  std::sort(ok.begin(), ok.end(), [&](auto a, auto b) { return a->cost(per_frame) < b->cost(per_frame); });
  std::vector<cv::Point> front;
  double best = 1e30;
  for (const auto* r : ok)
    if (r->err.rms < best) best = r->err.rms, front.push_back({int(px(r->cost(per_frame))), int(py(r->err.rms))});
  for (size_t i = 1; i < front.size(); ++i) cv::line(img, front[i - 1], front[i], black, 2);
  for (const auto* r : ok) {
    const cv::Point p{int(px(r->cost(per_frame))), int(py(r->err.rms))};
    const cv::Scalar c = colour.at(r->config.family());
    if (r->config.dynamic())
      cv::circle(img, p, 5, c, -1);
    else
      cv::rectangle(img, p - cv::Point(5, 5), p + cv::Point(5, 5), c, -1);
  }
  int ly = T + 10;
  for (const auto& f : families) {
    cv::circle(img, {W - R + 15, ly}, 5, colour.at(f), -1);
    cv::putText(img, f, {W - R + 25, ly + 4}, cv::FONT_HERSHEY_SIMPLEX, 0.38, black);
    ly += 16;
  }
  cv::putText(img, "dot: dynamic", {W - R + 10, ly + 10}, cv::FONT_HERSHEY_SIMPLEX, 0.4, black);
  cv::putText(img, "square: static", {W - R + 10, ly + 28}, cv::FONT_HERSHEY_SIMPLEX, 0.4, black);
  cv::putText(img, "line: Pareto front", {W - R + 10, ly + 46}, cv::FONT_HERSHEY_SIMPLEX, 0.4, black);
  cv::imwrite(path.string(), img);
}

// A message as one CSV field: no commas, quotes or line breaks.
std::string csv_text(std::string t) {
  for (char& ch : t)
    if (ch == ',' || ch == '"' || ch == '\n' || ch == '\r') ch = ch == ',' ? ';' : ' ';
  return t;
}

// Runs one configuration; fills its timings, its error against `ref_u` at `ref_points` (and against
// `analytic` when given) and, for dynamic runs, the error per frame.
Result run_config(const Spec& sp, const Config& c, const std::vector<double>& ref_points, const std::vector<double>& ref_u,
                  const std::vector<double>& analytic) {
  Result r;
  r.config = c;
  r.label = c.label();
  std::cerr << sp.name << ": " << r.label << " ... " << std::flush;
  const std::vector<uint8_t> use(ref_points.size() / 3, 1);
  try {
    const Scenario s = parse_scenario(scenario_text(sp, c), c.level->dir / "run.yaml", c.level->dir);
    RunReport rep;
    const Trajectory t = run_scenario(s, &rep);
    const Transfer tr = make_transfer(t.rest_vertices, ref_points);
    r.nodes = rep.particles;
    r.dt = rep.dt_s;
    r.steps = rep.steps;
    r.total = rep.setup_s + rep.wall_s;
    const auto& fw = rep.frame_wall_s;
    const int64_t frames = t.frame_count();
    if (!c.dynamic() && frames > 2) {
      r.setup = rep.setup_s + fw[1];
      r.frame = (fw.back() - fw[1]) / static_cast<double>(frames - 2);
    } else if (!c.dynamic()) {
      r.setup = rep.setup_s;
      r.frame = rep.wall_s;
    } else {
      r.setup = rep.setup_s;
      r.frame = rep.wall_s / (t.time.back() * 60);
    }
    for (int64_t f = 1; f < frames; ++f) {
      if (!c.dynamic() && f != frames - 1) continue;
      const auto u = carried_displacement(t, f, tr);
      const Error e = error_of(u, ref_u, use);
      r.curve_time.push_back(t.time[static_cast<size_t>(f)]);
      r.curve_wall.push_back(rep.setup_s + fw[static_cast<size_t>(f)]);
      r.curve_rms.push_back(e.rms);
      r.curve_max.push_back(e.max);
      if (f == frames - 1) {
        r.err = e;
        r.final_u = u;
        if (!analytic.empty()) r.analytic = error_of(u, analytic, use);
      }
    }
    const auto& vol = t.metric("enclosed_volume")->values;
    r.volume_change = 100 * (vol.back() / vol.front() - 1);
    r.ok = true;
    std::cerr << "setup " << r.setup << " s, " << r.frame << " s/frame, RMS " << r.err.rms << " mm\n";
  } catch (const std::exception& e) {
    r.failure = e.what();
    std::cerr << "failed: " << r.failure << "\n";
  }
  return r;
}

// The reference displacements at `points`: Neo-Hookean static on quadratic tets at `level`, cached.
std::vector<double> reference(const Spec& sp, const Level& level, const std::vector<double>& points, const fs::path& cache) {
  const size_t np = points.size() / 3;
  std::vector<double> u(3 * np);
  if (std::ifstream in{cache, std::ios::binary}) {
    uint64_t n = 0;
    in.read(reinterpret_cast<char*>(&n), sizeof n);
    if (n == np) {
      in.read(reinterpret_cast<char*>(u.data()), static_cast<std::streamsize>(8 * u.size()));
      if (in) return u;
    }
  }
  Config c;
  c.model = "fem";
  c.law = "neo_hookean";
  c.solver = "static";
  c.order = 2;
  c.tolerance_mm = 1e-4;
  c.level = &level;
  std::cerr << sp.name << ": reference (" << c.label() << ")...\n";
  const auto t0 = std::chrono::steady_clock::now();
  const Scenario s = parse_scenario(scenario_text(sp, c, true), level.dir / "reference.yaml", level.dir);
  RunReport rep;
  const Trajectory t = run_scenario(s, &rep);
  const Transfer tr = make_transfer(t.rest_vertices, points);
  u = carried_displacement(t, t.frame_count() - 1, tr);
  std::cerr << sp.name << ": reference took " << std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() << " s ("
            << rep.particles << " nodes)\n";
  std::ofstream o(cache, std::ios::binary);
  const uint64_t n = np;
  o.write(reinterpret_cast<const char*>(&n), sizeof n);
  o.write(reinterpret_cast<const char*>(u.data()), static_cast<std::streamsize>(8 * u.size()));
  if (!o) throw RuntimeError("time_vs_error: could not write " + cache.string());
  return u;
}

}  // namespace

int main(int argc, char** argv) {
  fs::path inputs, out;
  std::string which = "cantilever,kidney,heart";
  bool quick = false, local_only = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--inputs" && i + 1 < argc) inputs = argv[++i];
    else if (a == "--out" && i + 1 < argc) out = argv[++i];
    else if (a == "--scenarios" && i + 1 < argc) which = argv[++i];
    else if (a == "--quick") quick = true;
    else if (a == "--local-only") local_only = true;
    else {
      std::cerr << "usage: time_vs_error --inputs DIR --out DIR [--scenarios cantilever,kidney,heart] [--quick] [--local-only]\n";
      return 2;
    }
  }
  if (out.empty()) {
    std::cerr << "time_vs_error: --out is required\n";
    return 2;
  }
  fs::create_directories(out);
  std::vector<Spec> specs;
  if (which.find("cantilever") != std::string::npos) {
    Spec s;
    s.name = "cantilever";
    s.cantilever = true;
    for (const double h : quick ? std::vector<double>{4, 2, 1.6} : std::vector<double>{4, 2, 1.6, 1.3333333, 1})
      s.levels.push_back({h, out / "inputs" / "cantilever" / ("h" + std::to_string(h).substr(0, 4))});
    s.reference_level = quick ? 1 : 2;  // quadratic at h 2 (quick) or 1.6
    s.material = "  youngs_modulus_pa: 30000\n  poisson_ratio: 0.3\n";
    s.fixed = "fixed:\n  - box: {min: [-10, -1, -1], max: [0.01, 9, 9]}\n";
    s.tools = "tools:\n  - force:\n      radius_mm: 4.5\n      force_n: [0, 0, -0.001]\n      path:\n        - {t: 0, position_mm: [40, 4, 4]}\n";
    s.settle_s = 0.5;
    s.damping = 50;
    specs.push_back(s);
  }
  auto organ_levels = [&](const std::string& organ, std::vector<std::string> names) {
    std::vector<Level> ls;
    for (const auto& n : names) ls.push_back({std::stod(n), inputs / organ / ("v" + n)});
    return ls;
  };
  if (which.find("kidney") != std::string::npos) {
    Spec s;
    s.name = "kidney";
    s.levels = organ_levels("kidney", quick ? std::vector<std::string>{"6", "4.5", "3"} : std::vector<std::string>{"6", "4.5", "3", "2.25", "1.8"});
    s.reference_level = quick ? 2 : 3;  // quadratic at h 3 (quick) or 2.25
    s.material = "  preset: kidney\n";
    s.fixed = "fixed:\n  - box_fraction: {min: [0, 0.8, 0], max: [1, 1, 1]}\n";
    s.tools = "tools:\n  - force:\n      radius_mm: 6\n      snap_to_tissue: true\n      force_n: [0, 0.2, 0]\n      path:\n"
              "        - {t: 0, at_fraction: [0.5, 0.0, 0.5]}\n";
    s.settle_s = 0.4;
    s.damping = 100;
    specs.push_back(s);
  }
  if (which.find("heart") != std::string::npos) {
    Spec s;
    s.name = "heart";
    s.levels = organ_levels("heart", quick ? std::vector<std::string>{"7.2", "4.8"} : std::vector<std::string>{"7.2", "4.8", "3.6", "2.4"});
    s.reference_level = quick ? 1 : 2;  // quadratic at h 4.8 (quick) or 3.6
    s.material = "  preset: myocardium\n";
    s.fixed = "fixed:\n  - box_fraction: {min: [0, 0, 0.85], max: [1, 1, 1]}\n";
    s.move_s = 0.25;
    s.tools = "tools:\n  - grab:\n      radius_mm: 8\n      snap_to_tissue: true\n      path:\n"
              "        - {t: 0, at_fraction: [0.75, 0.0, 0.2]}\n        - {t: 0.25, offset_mm: [5, -12.5, -5]}\n";
    s.settle_s = 0.35;
    s.damping = 60;
    s.per_frame = true;
    specs.push_back(s);
  }

  std::ofstream runs(out / "runs.csv"), curves(out / "curves.csv"), budgets(out / "budgets.md"), local(out / "local_region.md");
  local << "Local region (fem_local_region.h) against the full Neo-Hookean static solve on the same mesh (linear tets, default "
           "tolerance). Near: the reference surface within " << kNearMm << " mm (rest) of its most displaced vertex (where the tool "
           "acts); far: the rest. Errors at the last frame, mm; time per frame after the first (heart) or setup + solve.\n";
  runs << "scenario,configuration,model,law,solver,elements,tolerance_mm,level_mm,nodes,dt_s,safety,steps,setup_s,frame_s,total_s,"
          "rms_mm,max_mm,volume_change_pct,analytic_rms_mm,analytic_max_mm,status\n";
  curves << "scenario,configuration,sim_time_s,wall_s,rms_mm,max_mm\n";
  const std::vector<double> budget_list{0.05, 0.1, 0.25, 0.5, 1.0, 2.0};

  for (const Spec& sp : specs) {
    if (sp.cantilever)
      for (const auto& l : sp.levels) write_cantilever(l);
    const Level& ref_level = sp.levels[sp.reference_level];
    const Level& fine = sp.levels.back();
    // Reference points: the finest level's rest surface (for the cantilever the tet models' surface, x >= 0).
    const SurfaceMesh ref_surface = read_surface_mesh_file(fine.dir / (sp.cantilever ? "surface_fem.h5" : "surface.h5"));
    const std::vector<double> ref_points(ref_surface.vertices.begin(), ref_surface.vertices.end());
    const size_t np = ref_points.size() / 3;
    const std::vector<double> ref_u = reference(sp, ref_level, ref_points, out / ("reference_" + sp.name + ".bin"));
    double ref_scale = 0;
    for (size_t p = 0; p < np; ++p) ref_scale += ref_u[3 * p] * ref_u[3 * p] + ref_u[3 * p + 1] * ref_u[3 * p + 1] + ref_u[3 * p + 2] * ref_u[3 * p + 2];
    ref_scale = std::sqrt(ref_scale / static_cast<double>(np));
    std::vector<double> analytic;
    if (sp.cantilever) {
      const double F = -1000, E = 30000, I = 8.0 * 8 * 8 * 8 / 12, Lb = 40, zc = 4;  // uN, Pa, mm^4, mm
      for (size_t p = 0; p < np; ++p) {
        const double x = ref_points[3 * p], z = ref_points[3 * p + 2];
        const double w = F * x * x * (3 * Lb - x) / (6 * E * I), dw = F * x * (2 * Lb - x) / (2 * E * I);
        analytic.insert(analytic.end(), {-(z - zc) * dw, 0.0, w});
      }
      const Error e = error_of(ref_u, analytic, std::vector<uint8_t>(np, 1));
      std::cerr << "cantilever: reference vs Euler-Bernoulli: RMS " << e.rms << " mm, max " << e.max << " mm\n";
    }

    std::vector<Config> configs;
    const auto add = [&](Config c) { configs.push_back(std::move(c)); };
    for (size_t li = 0; li < sp.levels.size(); ++li) {
      const Level* l = &sp.levels[li];
      const bool coarse = li < 2, finest = li + 1 == sp.levels.size();
      // The local region (issue 20): Newton within R mm of the tool, the rest linear; against the full
      // solve on the same mesh in local_region.md.
      const auto add_local = [&] {
        for (const double R : {10.0, 20.0, 40.0}) add({"fem", "neo_hookean", "static", 1, 0, "", 0.5, l, R, 0});
        add({"fem", "neo_hookean", "static", 1, 0, "", 0.5, l, 20, 20});
      };
      if (local_only) {
        add({"fem", "linear", "static", 1, 0, "", 0.5, l});
        add({"fem", "neo_hookean", "static", 1, 0, "", 0.5, l});
        add_local();
        continue;
      }
      add_local();
      for (const double sf : {0.5, 0.9}) add({"spring_grid", "", "dynamic", 1, 0, "", sf, l});
      if (!finest || !sp.per_frame) add({"explicit_springs", "", "dynamic", 1, 0, "", 0.5, l});
      // Static FEM on linear tets: every law; the nonlinear ones at the default tolerance and at budgets in mm.
      add({"fem", "linear", "static", 1, 0, "", 0.5, l});
      for (const std::string law : {"corotational", "neo_hookean"}) {
        add({"fem", law, "static", 1, 0, "", 0.5, l});
        for (const double tol : {0.01, 0.1}) add({"fem", law, "static", 1, tol, "", 0.5, l});
      }
      if (!finest) add({"fem", "stvk", "static", 1, 0, "", 0.5, l});
      if (li == 1) add({"fem", "neo_hookean", "static", 1, 0.01, "iterative", 0.5, l});  // the iterative path, for comparison
      // Quadratic tets up to the reference's level (the reference itself is not a configuration).
      if (li <= sp.reference_level) {
        add({"fem", "linear", "static", 2, 0, "", 0.5, l});
        for (const std::string law : {"corotational", "neo_hookean"})
          for (const double tol : {0.01, 0.1})
            if (li < sp.reference_level || law != "neo_hookean") add({"fem", law, "static", 2, tol, "", 0.5, l});
        if (li + 1 == sp.reference_level) add({"fem", "neo_hookean", "static", 2, 1e-4, "", 0.5, l});  // the reference's error
      }
      // Implicit dynamics (a frame a step) and explicit dynamics (the coarse levels: its step follows
      // the smallest tet altitude).
      if (coarse) {
        for (const std::string law : {"corotational", "neo_hookean"}) add({"fem", law, "implicit", 1, 0.1, "", 0.5, l});
        add({"fem", "corotational", "implicit", 2, 0.1, "", 0.5, l});
        for (const double sf : {0.5, 0.9}) add({"fem", "neo_hookean", "dynamic", 1, 0, "", sf, l});
      }
    }
    std::vector<Result> results;
    for (const Config& c : configs) {
      Result r = run_config(sp, c, ref_points, ref_u, analytic);
      runs << sp.name << "," << r.label << "," << c.model << "," << c.law << "," << (c.model == "fem" ? c.solver : "dynamic") << ","
           << (c.order == 2 ? "quadratic" : "linear") << "," << c.tolerance_mm << "," << c.level->h << "," << r.nodes << "," << r.dt << ","
           << c.safety << "," << r.steps << "," << r.setup << "," << r.frame << "," << r.total << "," << r.err.rms << "," << r.err.max
           << "," << r.volume_change << "," << (sp.cantilever ? r.analytic.rms : NAN) << "," << (sp.cantilever ? r.analytic.max : NAN)
           << "," << (r.ok ? "ok" : "failed: " + csv_text(r.failure)) << "\n";
      if (c.dynamic())
        for (size_t i = 0; i < r.curve_rms.size(); ++i)
          curves << sp.name << "," << r.label << "," << r.curve_time[i] << "," << r.curve_wall[i] << "," << r.curve_rms[i] << ","
                 << r.curve_max[i] << "\n";
      runs.flush(), curves.flush();
      results.push_back(std::move(r));
    }
    // Near and far from the tool: the reference surface within kNearMm of its most displaced vertex.
    std::vector<uint8_t> near(np, 0), far(np, 0);
    {
      size_t peak = 0;
      double peak_u = -1;
      for (size_t p = 0; p < np; ++p) {
        const double u2 = ref_u[3 * p] * ref_u[3 * p] + ref_u[3 * p + 1] * ref_u[3 * p + 1] + ref_u[3 * p + 2] * ref_u[3 * p + 2];
        if (u2 > peak_u) peak_u = u2, peak = p;
      }
      for (size_t p = 0; p < np; ++p) {
        double d2 = 0;
        for (int c = 0; c < 3; ++c) d2 += (ref_points[3 * p + c] - ref_points[3 * peak + c]) * (ref_points[3 * p + c] - ref_points[3 * peak + c]);
        near[p] = d2 <= kNearMm * kNearMm;
        far[p] = !near[p];
      }
    }
    local << "\n#### " << sp.name << "\n\n| h (mm) | configuration | " << (sp.per_frame ? "time per frame" : "setup + solve")
          << " | near RMS / max | far RMS / max | vs the reference (RMS) |\n|---:|---|---:|---|---|---:|\n";
    for (const Level& l : sp.levels) {
      const Result* full = nullptr;
      for (const auto& r : results)
        if (r.ok && r.config.level == &l && r.config.model == "fem" && r.config.law == "neo_hookean" && r.config.solver == "static" &&
            r.config.order == 1 && r.config.tolerance_mm == 0 && r.config.local_mm == 0)
          full = &r;
      if (!full) continue;
      for (const auto& r : results) {
        if (!r.ok || r.config.level != &l || r.config.model != "fem" || r.config.solver != "static" || r.config.order != 1 ||
            r.config.tolerance_mm != 0 || !r.config.linear.empty() || (r.config.law != "linear" && r.config.law != "neo_hookean"))
          continue;
        const Error n = error_of(r.final_u, full->final_u, near), f = error_of(r.final_u, full->final_u, far);
        char buf[512];
        std::snprintf(buf, sizeof buf, "| %g | %s | %.3g s | %.3g / %.3g | %.3g / %.3g | %.3g |\n", l.h, r.label.c_str(), r.cost(sp.per_frame),
                      n.rms, n.max, f.rms, f.max, r.err.rms);
        local << buf;
      }
    }
    local.flush();
    pareto_png(sp.name + ": " + (sp.per_frame ? "time per frame" : "time") + " vs error", results, sp.per_frame,
               out / ("pareto_" + sp.name + ".png"));
    // The reference's own error: the same model one level coarser (Richardson, p = 2 and 3).
    const Level& coarser = sp.levels[sp.reference_level - 1];
    double d = -1;
    for (const auto& r : results)
      if (r.ok && r.config.level == &coarser && r.config.model == "fem" && r.config.law == "neo_hookean" && r.config.order == 2 &&
          r.config.solver == "static" && r.config.tolerance_mm == 1e-4)
        d = r.err.rms;
    const double ratio = coarser.h / ref_level.h;
    char head[512];
    std::snprintf(head, sizeof head,
                  "\n#### %s (reference: Neo-Hookean static on quadratic tets, h %.3g mm; RMS displacement %.3g mm)\n\n"
                  "The same model at h %.3g mm is %.3g mm RMS from it: the reference's own error is about %.2g mm (p = 3) to "
                  "%.2g mm (p = 2), Richardson with h ratio %.3g.%s\n\n",
                  sp.name.c_str(), ref_level.h, ref_scale, coarser.h, d, d / (std::pow(ratio, 3) - 1), d / (std::pow(ratio, 2) - 1), ratio,
                  sp.cantilever ? " Euler-Bernoulli errors: runs.csv." : "");
    budgets << head;
    budgets << "| RMS error budget | fastest configuration | " << (sp.per_frame ? "time per frame" : "setup + solve") << " | setup | its RMS / max | runner-up |\n"
            << "|---:|---|---:|---:|---|---|\n";
    for (const double b : budget_list) {
      std::vector<const Result*> within;
      for (const auto& r : results)
        if (r.ok && r.err.rms <= b) within.push_back(&r);
      std::sort(within.begin(), within.end(), [&](auto x, auto y) { return x->cost(sp.per_frame) < y->cost(sp.per_frame); });
      char buf[512];
      if (within.empty()) {
        std::snprintf(buf, sizeof buf, "| %g mm | none | | | | |\n", b);
        budgets << buf;
        continue;
      }
      const Result& w = *within[0];
      std::snprintf(buf, sizeof buf, "| %g mm | %s | %.3g s | %.3g s | %.3g / %.3g mm | ", b, w.label.c_str(), w.cost(sp.per_frame), w.setup,
                    w.err.rms, w.err.max);
      budgets << buf;
      if (within.size() > 1) {
        std::snprintf(buf, sizeof buf, "%s (%.3g s)", within[1]->label.c_str(), within[1]->cost(sp.per_frame));
        budgets << buf;
      }
      budgets << " |\n";
    }
    budgets.flush();
  }
  return 0;
}
