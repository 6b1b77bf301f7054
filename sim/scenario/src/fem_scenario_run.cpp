// Running a scenario with a tetrahedral FEM model (scenario kind: fem): the tet mesh, one material law,
// fixed regions, grab tools as prescribed displacements of the nodes they capture, probes as sphere
// contact (dynamic only), gravity; the surface embedded in the tets (tet_embedding.h). Two solvers:
//   dynamic: explicit central differences (fem_explicit_dynamics.h), the tools updated every step;
//   static:  at every output frame, the equilibrium under that frame's grab displacements, forces and
//            gravity, a quasi-static sequence: the linear material by the factorised, condensed solver
//            (fem_linear_static_solver.h: one factorisation for the run), the nonlinear laws by Newton
//            with conjugate gradients (fem_static_solver.h).
// Same trajectory layout and metrics as the spring models (scenario_run.h), plus the static solver's
// newton_iterations and cg_iterations per frame.
#include "ctsurg/core/error.h"
#include "ctsurg/core/file_hash.h"
#include "ctsurg/core/memory_guard.h"
#include "ctsurg/core/surface_mesh_file.h"
#include "ctsurg/core/tet_mesh_file.h"
#include "ctsurg/sim/base/fixed_regions.h"
#include "ctsurg/sim/fem/fem_explicit_dynamics.h"
#include "ctsurg/sim/fem/fem_forces.h"
#include "ctsurg/sim/fem/fem_linear_static_solver.h"
#include "ctsurg/sim/fem/fem_model.h"
#include "ctsurg/sim/fem/fem_static_solver.h"
#include "ctsurg/sim/surface/surface_coupling.h"
#include "ctsurg/sim/surface/tet_embedding.h"
#include "scenario_support.h"

#include <chrono>
#include <numeric>
#include <optional>
#include <set>

namespace ctsurg::sim::detail {

namespace {

struct FemGrab {
  const ToolAction* spec = nullptr;
  ResolvedPath path;
  std::vector<int32_t> nodes;  // captured nodes (increasing); empty before capture
  Vec3 captured_at{0, 0, 0};   // the tool's position at capture
  double capture_time = -1;
  bool released = false;
  bool active(double t) const { return t >= spec->start_s - 1e-12 && t < spec->end_s; }
};

FemMaterialModel law_of(FemLaw law) {
  return law == FemLaw::linear ? FemMaterialModel::linear : law == FemLaw::stvk ? FemMaterialModel::stvk : FemMaterialModel::neo_hookean;
}

}  // namespace

Trajectory run_fem_scenario(const Scenario& s, RunReport* report_out, const std::function<void(double)>& progress) {
  RunReport report;
  const std::string sfile = s.file.string();
  // cuda: the explicit dynamics on the device, and the nonlinear static solver's conjugate gradients;
  // the linear static solver's factorisation stays on the CPU.
  const Backend backend = resolve_backend(s.backend, sfile + ": backend");

  // The mesh in a local frame (see scenario_run.cpp: float precision far from the CT origin).
  TetMesh mesh = read_tet_mesh_file(s.tetmesh);
  const Bounds lps_bounds = bounds_of(mesh.nodes);
  const Vec3 origin = local_origin(lps_bounds.lo, lps_bounds.hi);
  for (size_t i = 0; i < mesh.nodes.size(); ++i) mesh.nodes[i] -= origin[i % 3];
  FemMaterial material;
  material.model = law_of(s.fem_law);
  material.youngs_modulus = s.material.youngs_modulus_pa;
  material.poisson_ratio = s.material.poisson_ratio;
  material.density = s.material.density;
  const FemModel model = build_fem_model(mesh, material);
  const std::vector<double>& rest = model.nodes;
  const int64_t nn = model.node_count();
  report.particles = nn;
  report.elements = model.tet_count();
  const Bounds bounds = bounds_of(rest);

  // Fixed regions (nodes).
  std::vector<Real> rest_real(rest.begin(), rest.end());
  const std::vector<int32_t> fixed_nodes =
      fixed_particles(s, rest_real, bounds, origin, [&](uint16_t label) { return nodes_with_label(mesh, label); });
  const std::set<int32_t> fixed(fixed_nodes.begin(), fixed_nodes.end());
  report.fixed = static_cast<int64_t>(fixed_nodes.size());

  // Surface embedded in the tets.
  const bool has_surface = !s.surface.empty();
  SurfaceMesh surface;
  SurfaceCoupling coupling;
  std::vector<float> local_rest_vertices;
  if (has_surface) {
    surface = read_surface_mesh_file(s.surface);
    local_rest_vertices.resize(surface.vertices.size());
    for (size_t i = 0; i < surface.vertices.size(); ++i) {
      local_rest_vertices[i] = static_cast<float>(static_cast<double>(surface.vertices[i]) - origin[i % 3]);
    }
    TetEmbeddingStats st;
    coupling = embed_surface_in_tets(local_rest_vertices, mesh, 10.0, &st);
    report.notes.push_back("surface: " + std::to_string(st.inside) + " vertices inside tets, " + std::to_string(st.outside) +
                           " outside (at most " + std::to_string(st.max_outside_mm) + " mm)");
  }

  // Tools.
  std::vector<FemGrab> grabs;
  std::vector<std::pair<const ToolAction*, ResolvedPath>> probes;
  std::vector<FemGrab> forces;  // force tools: the nodes sharing the force (captured like a grab)
  std::vector<std::string> sphere_kinds;
  for (const auto& t : s.tools) {
    std::string note;
    ResolvedPath path = resolve_path(t, bounds, rest, origin, &note);
    if (!note.empty()) report.notes.push_back(note);
    if (t.kind == ToolAction::Kind::grab) {
      FemGrab g;
      g.spec = &t;
      g.path = std::move(path);
      grabs.push_back(std::move(g));
    } else if (t.kind == ToolAction::Kind::probe) {
      probes.emplace_back(&t, std::move(path));
    } else if (t.kind == ToolAction::Kind::force) {
      FemGrab g;
      g.spec = &t;
      g.path = std::move(path);
      forces.push_back(std::move(g));
    } else {
      throw InputError(sfile, t.label, "the FEM models do not cut; use a spring model");
    }
  }
  for (const auto& t : s.tools) sphere_kinds.push_back(to_string(t.kind));

  const bool dynamic = s.fem_solver == FemSolver::dynamic;
  std::optional<FemExplicitDynamics> dyn;
  double dt = 0;
  if (dynamic) {
    const FemCriticalStep crit = fem_critical_time_step(model, s.safety_factor);
    report.critical_dt_s = crit.critical;
    FemDynamicsOptions o;
    o.dt = s.dt_s > 0 ? s.dt_s : crit.dt;
    o.safety_factor = s.safety_factor;
    o.mass_damping = s.damping_per_s;
    o.gravity = s.gravity;
    o.threads = s.threads;
    if (o.dt > crit.critical) {
      throw InputError(sfile, "time.dt_s", "the step " + std::to_string(o.dt) + " s is above the FEM critical step " +
                                              std::to_string(crit.critical) + " s (element " + std::to_string(crit.element) +
                                              ", " + std::to_string(crit.length) + " mm); use auto or a smaller step");
    }
    dyn.emplace(model, o, backend);
    dyn->set_fixed_nodes(fixed_nodes);
    dt = dyn->dt();
    report.notes.push_back("FEM " + std::string(to_string(s.fem_law)) + " explicit dynamics, dt " + std::to_string(dt) +
                           " s (critical " + std::to_string(crit.critical) + " s, element " + std::to_string(crit.element) + ")");
  } else if (fixed_nodes.empty()) {
    throw InputError(sfile, "fixed", "a static FEM problem needs fixed nodes (the system is singular otherwise)");
  }

  // Output.
  const int64_t frame_count = static_cast<int64_t>(std::floor(s.duration_s / s.frame_interval_s + 1e-9)) + 1;
  const int64_t nv = has_surface ? surface.vertex_count() : nn;
  check_allocation(static_cast<uint64_t>(frame_count), static_cast<uint64_t>(12 * nv + (s.write_particles ? 12 * nn : 0) + 64),
                   sfile, "output.frame_interval_s");
  Trajectory traj;
  traj.scenario = s.name;
  traj.model = std::string("fem ") + to_string(s.fem_law) + (dynamic ? " (dynamic)" : " (static)");
  if (has_surface) {
    traj.surface_file = s.surface.string();
    traj.surface_sha256 = sha256_file(s.surface);
    traj.rest_vertices = surface.vertices;
    traj.topologies.push_back(surface.triangles);
  } else {
    traj.rest_vertices.resize(rest.size());
    for (size_t i = 0; i < rest.size(); ++i) traj.rest_vertices[i] = static_cast<float>(rest[i] + origin[i % 3]);
    traj.topologies.emplace_back();
  }
  if (s.write_particles) {
    traj.rest_particles.resize(rest.size());
    for (size_t i = 0; i < rest.size(); ++i) traj.rest_particles[i] = static_cast<float>(rest[i] + origin[i % 3]);
  }
  std::vector<TrajectoryMetric> metrics = {
      {"kinetic_energy", "nJ", {}},     {"elastic_energy", "nJ", {}}, {"max_displacement", "mm", {}},
      {"surface_max_displacement", "mm", {}}, {"enclosed_volume", "mm^3", {}}, {"surface_area", "mm^2", {}},
      {"springs_cut", "1", {}},         {"dt", "s", {}},             {"newton_iterations", "1", {}},
      {"cg_iterations", "1", {}}};

  std::vector<double> u(static_cast<size_t>(3 * nn), 0.0);
  ParticleState positions(rest_real, std::vector<Real>(static_cast<size_t>(nn), Real(1)));
  std::vector<float> vertices;
  int newton = 0, cg = 0;
  const auto record_frame = [&](double t) {
    for (int64_t i = 0; i < nn; ++i) {
      positions.x[static_cast<size_t>(i)] = static_cast<Real>(rest[static_cast<size_t>(3 * i)] + u[static_cast<size_t>(3 * i)]);
      positions.y[static_cast<size_t>(i)] = static_cast<Real>(rest[static_cast<size_t>(3 * i + 1)] + u[static_cast<size_t>(3 * i + 1)]);
      positions.z[static_cast<size_t>(i)] = static_cast<Real>(rest[static_cast<size_t>(3 * i + 2)] + u[static_cast<size_t>(3 * i + 2)]);
    }
    if (has_surface) {
      move_surface(coupling, positions, rest_real, vertices, backend, s.threads);
    } else {
      vertices.resize(static_cast<size_t>(3 * nn));
      for (size_t i = 0; i < vertices.size(); ++i) vertices[i] = static_cast<float>(rest[i] + u[i]);
    }
    traj.time.push_back(t);
    for (size_t i = 0; i < vertices.size(); ++i) traj.vertices.push_back(static_cast<float>(vertices[i] + origin[i % 3]));
    traj.topology_of_frame.push_back(0);
    if (s.write_particles) {
      for (size_t i = 0; i < rest.size(); ++i) traj.particles.push_back(static_cast<float>(rest[i] + u[i] + origin[i % 3]));
    }
    double max_u = 0, max_v = 0;
    for (int64_t i = 0; i < nn; ++i) {
      const double* d = &u[static_cast<size_t>(3 * i)];
      max_u = std::max(max_u, d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    }
    const std::vector<float>& rv = has_surface ? local_rest_vertices : vertices;
    for (size_t i = 0; has_surface && i < vertices.size(); i += 3) {
      double d = 0;
      for (size_t c = 0; c < 3; ++c) d += std::pow(double(vertices[i + c]) - rv[i + c], 2);
      max_v = std::max(max_v, d);
    }
    metrics[0].values.push_back(dyn ? dyn->kinetic_energy() : 0.0);
    metrics[1].values.push_back(dyn ? dyn->strain_energy() : fem_strain_energy(model, u));
    metrics[2].values.push_back(std::sqrt(max_u));
    metrics[3].values.push_back(has_surface ? std::sqrt(max_v) : std::sqrt(max_u));
    metrics[4].values.push_back(has_surface ? enclosed_volume(vertices, surface.triangles) : 0.0);
    metrics[5].values.push_back(has_surface ? surface_area(vertices, surface.triangles) : 0.0);
    metrics[6].values.push_back(0.0);
    metrics[7].values.push_back(dt);
    metrics[8].values.push_back(newton);
    metrics[9].values.push_back(cg);
    size_t gi = 0, pi = 0, fi = 0;
    for (const auto& tool : s.tools) {
      Vec3 c{0, 0, 0};
      bool on = false;
      if (tool.kind == ToolAction::Kind::grab || tool.kind == ToolAction::Kind::force) {
        const FemGrab& g = tool.kind == ToolAction::Kind::grab ? grabs[gi++] : forces[fi++];
        c = g.path.at(t);
        on = g.active(t) && !g.nodes.empty();
      } else {
        const auto& p = probes[pi++];
        c = p.second.at(t);
        on = t >= tool.start_s - 1e-12 && t < tool.end_s;
      }
      traj.spheres.insert(traj.spheres.end(), {c[0] + origin[0], c[1] + origin[1], c[2] + origin[2], on ? tool.radius_mm : 0.0});
    }
  };
  // A grab captures the free nodes inside its sphere once, at time `t` (its start), with their
  // displacement then; afterwards they are held at that displacement plus the tool's travel.
  std::vector<std::vector<double>> capture_u(grabs.size());
  // The free nodes inside a sphere (centre c, radius r) at displacement cur_u, increasing.
  const auto free_nodes_in_sphere = [&](const Vec3& c, double r, const std::vector<double>& cur_u) {
    std::vector<int32_t> ids;
    for (int64_t i = 0; i < nn; ++i) {
      double d = 0;
      for (size_t a = 0; a < 3; ++a) d += std::pow(rest[static_cast<size_t>(3 * i) + a] + cur_u[static_cast<size_t>(3 * i) + a] - c[a], 2);
      if (d < r * r && !fixed.count(static_cast<int32_t>(i))) ids.push_back(static_cast<int32_t>(i));
    }
    return ids;
  };
  const auto capture = [&](size_t gi, double t, const std::vector<double>& cur_u) {
    FemGrab& g = grabs[gi];
    const Vec3 c = g.path.at(t);
    g.nodes = free_nodes_in_sphere(c, g.spec->radius_mm, cur_u);
    if (g.nodes.empty()) {
      throw InputError(sfile, g.spec->label, "grabs no free node at t = " + std::to_string(t) +
                                                 " s; move it onto the tissue or set snap_to_tissue: true");
    }
    g.captured_at = c;
    g.capture_time = t;
    capture_u[gi].clear();
    for (const int32_t n : g.nodes) {
      for (int k = 0; k < 3; ++k) capture_u[gi].push_back(cur_u[static_cast<size_t>(3 * n + k)]);
    }
    report.notes.push_back(g.spec->label + ": grabbed " + std::to_string(g.nodes.size()) + " nodes at t = " + std::to_string(t) + " s");
  };
  // The prescribed nodes and displacements at time t (capturing grabs that start by t: at t in the
  // dynamic run, which reaches every step; at their start time in the static one).
  const auto grab_state = [&](double t, std::vector<int32_t>& nodes, std::vector<double>& disp, const std::vector<double>& cur_u,
                              bool capture_at_start) {
    nodes.clear();
    disp.clear();
    for (size_t gi = 0; gi < grabs.size(); ++gi) {
      FemGrab& g = grabs[gi];
      if (g.nodes.empty() && !g.released && g.active(t)) capture(gi, capture_at_start ? g.spec->start_s : t, cur_u);
      if (!g.nodes.empty() && !g.active(t)) {
        g.nodes.clear();
        g.released = true;
      }
      if (g.nodes.empty()) continue;
      const Vec3 c = g.path.at(t);
      for (size_t k = 0; k < g.nodes.size(); ++k) {
        nodes.push_back(g.nodes[k]);
        for (size_t a = 0; a < 3; ++a) disp.push_back(capture_u[gi][3 * k + a] + c[a] - g.captured_at[a]);
      }
    }
    // A node that two grabs hold follows the later one (listed once: the solvers take a node set).
    std::vector<int64_t> last(static_cast<size_t>(nn), -1);
    for (size_t k = 0; k < nodes.size(); ++k) last[static_cast<size_t>(nodes[k])] = static_cast<int64_t>(k);
    size_t kept = 0;
    for (size_t k = 0; k < nodes.size(); ++k) {
      if (last[static_cast<size_t>(nodes[k])] != static_cast<int64_t>(k)) continue;
      nodes[kept] = nodes[k];
      for (size_t a = 0; a < 3; ++a) disp[3 * kept + a] = disp[3 * k + a];
      ++kept;
    }
    nodes.resize(kept);
    disp.resize(3 * kept);
  };

  // The external nodal forces (uN, #N x 3; empty when no force acts) of the force tools active at t.
  // A force captures its nodes at t (dynamic) or at its start (static), from the displacement cur_u.
  // Rebuilt only when a force starts or ends; returns whether it changed.
  std::vector<double> nodal_forces;
  const auto update_forces = [&](double t, const std::vector<double>& cur_u, bool capture_at_start) {
    bool changed = false;
    for (auto& g : forces) {
      if (g.nodes.empty() && !g.released && g.active(t)) {
        g.nodes = free_nodes_in_sphere(g.path.at(capture_at_start ? g.spec->start_s : t), g.spec->radius_mm, cur_u);
        if (g.nodes.empty()) {
          throw InputError(sfile, g.spec->label, "the force's sphere holds no free node; move it onto the tissue or set snap_to_tissue: true");
        }
        report.notes.push_back(g.spec->label + ": force shared by " + std::to_string(g.nodes.size()) + " nodes");
        changed = true;
      }
      if (!g.nodes.empty() && !g.active(t)) {
        g.nodes.clear();
        g.released = true;
        changed = true;
      }
    }
    if (!changed) return false;
    nodal_forces.clear();
    for (const auto& g : forces) {
      if (g.nodes.empty()) continue;
      if (nodal_forces.empty()) nodal_forces.assign(static_cast<size_t>(3 * nn), 0.0);
      const double share = 1e6 / static_cast<double>(g.nodes.size());  // N -> uN
      for (const int32_t n : g.nodes) {
        for (size_t a = 0; a < 3; ++a) nodal_forces[static_cast<size_t>(3 * n) + a] += g.spec->force_n[a] * share;
      }
    }
    return true;
  };

  // Whether no tool acts (starts, moves or holds) in (t0, t1]: grabs, probes and forces alike.
  const auto tools_idle = [&](double t0, double t1) {
    for (const auto& t : s.tools) {
      if (t.end_s > t0 && t.start_s <= t1 + 1e-12) return false;
    }
    return true;
  };
  const auto start = std::chrono::steady_clock::now();
  record_frame(0.0);
  std::vector<int32_t> gnodes;
  std::vector<double> gdisp;
  if (dynamic) {
    double t = 0;
    int64_t next_frame = 1;
    bool had_grab = false;
    while (next_frame < frame_count) {
      const double t_next = t + dt;
      grab_state(t_next, gnodes, gdisp, u, false);
      if (!gnodes.empty()) {
        dyn->set_prescribed(gnodes, gdisp);
        had_grab = true;
      } else if (had_grab) {
        dyn->clear_prescribed();
        had_grab = false;
      }
      // One probe at a time is supported by the dynamics' contact sphere: the first active one.
      std::array<double, 3> centre{0, 0, 0};
      double radius = 0;
      for (const auto& [spec, path] : probes) {
        if (t_next >= spec->start_s - 1e-12 && t_next < spec->end_s) {
          const Vec3 c = path.at(t_next);
          centre = {c[0], c[1], c[2]};
          radius = spec->radius_mm;
          break;
        }
      }
      dyn->set_contact_sphere(centre, radius);
      if (update_forces(t_next, u, false)) dyn->set_external_forces(nodal_forces);
      // Tools move every step; while none acts until the next frame, the steps go in one call (on cuda:
      // one launch sequence and one wait instead of one per step).
      const double t_frame = static_cast<double>(next_frame) * s.frame_interval_s;
      const int steps = gnodes.empty() && radius == 0 && tools_idle(t_next, t_frame)
                            ? std::max(1, static_cast<int>(std::floor((t_frame - t) / dt + 0.5)))
                            : 1;
      try {
        dyn->step(steps);
      } catch (const RuntimeError& e) {
        throw RuntimeError(sfile + ": the FEM run became unstable: " + e.what());
      }
      report.steps += steps;
      t = dyn->time();
      if (t >= static_cast<double>(next_frame) * s.frame_interval_s - 0.5 * dt) {
        const auto d = dyn->displacements();
        u.assign(d.begin(), d.end());
        record_frame(t);
        ++next_frame;
        if (progress) progress(t / s.duration_s);
      }
    }
  } else {
    // Quasi-static: each frame's equilibrium under that frame's grabs and gravity. The linear material
    // factorises its constant stiffness once (fem_linear_static_solver.h); the nonlinear laws run
    // Newton with conjugate gradients per frame.
    FemBoundaryConditions bc;
    bc.fixed_nodes = fixed_nodes;
    FemLoads loads;
    loads.gravity = s.gravity;
    FemStaticOptions options;
    options.threads = s.threads;
    options.load_steps = 1;
    std::optional<FemLinearStaticSolver> linear;
    if (material.model == FemMaterialModel::linear) {
      FemLinearSolverOptions lo;
      lo.threads = s.threads;
      linear.emplace(model, bc, lo);
      report.notes.push_back("FEM linear static: stiffness factorised once (" + std::to_string(linear->stats().factor_nonzeros) +
                             " non-zeros, " + std::to_string(linear->stats().factor_seconds) + " s); each frame a condensed solve");
    }
    for (int64_t f = 1; f < frame_count; ++f) {
      const double t = static_cast<double>(f) * s.frame_interval_s;
      grab_state(t, gnodes, gdisp, u, true);
      update_forces(t, u, true);
      loads.forces = nodal_forces;
      FemStaticResult r;
      if (linear) {
        r = linear->solve(gnodes, gdisp, loads);
      } else {
        bc.prescribed_nodes = gnodes;
        bc.prescribed_displacements = gdisp;
        if (f > 1) options.initial_displacements = u;  // warm start from the previous frame
        r = solve_fem_static(model, bc, loads, options, backend);
      }
      if (!r.report.converged) {
        throw RuntimeError(sfile + ": the static FEM solve of frame " + std::to_string(f) + " (t = " + std::to_string(t) +
                           " s) did not converge: relative residual " + std::to_string(r.report.relative_residual) +
                           " after " + std::to_string(r.report.newton_iterations) + " Newton iterations");
      }
      u = r.displacements;
      newton = r.report.newton_iterations;
      cg = std::accumulate(r.report.cg_iterations.begin(), r.report.cg_iterations.end(), 0);
      report.steps += r.report.newton_iterations;
      record_frame(t);
      if (progress) progress(t / s.duration_s);
    }
  }
  report.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  report.dt_s = dt;
  traj.dt_s = dt;
  traj.metrics = std::move(metrics);
  traj.sphere_kinds = sphere_kinds;
  if (progress) progress(1.0);
  if (report_out) *report_out = std::move(report);
  return traj;
}

}  // namespace ctsurg::sim::detail
