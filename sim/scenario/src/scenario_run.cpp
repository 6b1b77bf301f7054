#include "ctsurg/sim/scenario/scenario_run.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/file_hash.h"
#include "ctsurg/core/memory_guard.h"
#include "ctsurg/core/occupancy_grid_file.h"
#include "ctsurg/core/surface_mesh_file.h"
#include "ctsurg/core/tet_mesh_file.h"
#include "ctsurg/sim/base/fixed_regions.h"
#include "ctsurg/sim/springs/sphere_tools.h"
#include "ctsurg/sim/springs/spring_calibration.h"
#include "ctsurg/sim/springs/spring_cutting.h"
#include "ctsurg/sim/springs/spring_mass_step.h"
#include "ctsurg/sim/springs/stability.h"
#include "ctsurg/sim/surface/surface_coupling.h"
#include "ctsurg/sim/surface/surface_cutting.h"
#include "ctsurg/sim/surface/tet_embedding.h"
#include "scenario_support.h"
#include "spring_engine.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <set>
#include <variant>

namespace ctsurg::sim {

namespace {

using namespace detail;
using Model = std::variant<SpringGridModel, ExplicitSpringModel>;

struct ToolState {
  const ToolAction* spec = nullptr;
  ResolvedPath path;
  std::optional<Grab> grab;  // captured particles while grabbing
  int grab_handle = -1;      // the engine's name for it (DeviceSimulation holds several)
  std::vector<int32_t> loaded;  // force: the particles sharing the force (captured at start)
  bool released = false;
  std::optional<double> cut_from;  // cut: the time the blade's current sweep started
  bool active(double t) const { return t >= spec->start_s - 1e-12 && t < spec->end_s; }
};

// Everything a restart after instability goes back to.
struct Checkpoint {
  ParticleState state;
  Model model;
  std::vector<ToolState> tools;
  std::vector<uint32_t> triangles;
  SurfaceCoupling coupling;
  double t = 0;
  int64_t steps = 0, springs_cut = 0, triangles_removed = 0;
  size_t frames = 0;
};

}  // namespace

Trajectory run_scenario(const Scenario& s, RunReport* report_out, const std::function<void(double)>& progress) {
  if (s.model == ModelKind::fem) return run_fem_scenario(s, report_out, progress);
  RunReport report;
  const std::string sfile = s.file.string();
  // cuda: InputError unless this build has CUDA and a device is present; auto: cuda exactly then.
  const Backend backend = resolve_backend(s.backend, sfile + ": backend");

  // The model.
  // The simulation runs in LPS shifted by `origin`, a whole-millimetre point near the grid's centre:
  // a heart at z = 650 mm would otherwise keep positions in float with a resolution of 6e-5 mm, and
  // spring lengths (differences of positions) lose relative precision with it. Inputs are shifted on
  // entry and outputs shifted back (in double before rounding to the file's float).
  OccupancyGrid grid = read_occupancy_grid_file(s.grid);
  const auto& dims = grid.occupancy.geometry.dims;
  const Eigen::Vector3d centre = grid.occupancy.geometry.index_to_world(
      0.5 * Eigen::Vector3d(static_cast<double>(dims[0] - 1), static_cast<double>(dims[1] - 1), static_cast<double>(dims[2] - 1)));
  const Vec3 origin{std::round(centre[0]), std::round(centre[1]), std::round(centre[2])};
  const Eigen::Vector3d shift(origin[0], origin[1], origin[2]);
  for (ImageGeometry* g : {&grid.occupancy.geometry, &grid.fraction.geometry, &grid.label.geometry, &grid.mask.geometry}) {
    g->origin -= shift;
  }
  std::optional<SpringGridModel> grid_model;
  std::optional<TetMesh> tetmesh;
  Model model;
  if (s.model == ModelKind::spring_grid || s.springs_from == SpringSource::grid) {
    grid_model = build_spring_grid_model(grid, calibrated_grid_material(s.material, grid.occupancy.geometry, s.mass_from_fraction));
    if (s.model == ModelKind::spring_grid) {
      model = *grid_model;
    } else {
      model = explicit_model_from_grid(*grid_model);
    }
  } else {
    tetmesh = read_tet_mesh_file(s.tetmesh);
    for (size_t i = 0; i < tetmesh->nodes.size(); ++i) tetmesh->nodes[i] -= origin[i % 3];
    model = calibrated_tet_spring_model(*tetmesh, s.material);
  }
  const auto& rest = std::visit([](const auto& m) -> const std::vector<Real>& { return m.rest_positions; }, model);
  ParticleState state = std::visit([](const auto& m) { return m.make_state(); }, model);
  report.particles = state.count();
  report.springs = std::visit([](const auto& m) -> int64_t {
    if constexpr (std::is_same_v<std::decay_t<decltype(m)>, SpringGridModel>) {
      return m.spring_count();
    } else {
      return m.alive_spring_count();
    }
  }, model);
  const Bounds bounds = bounds_of(rest);

  // Fixed regions.
  const std::vector<int32_t> fixed_ids = fixed_particles(s, rest, bounds, origin, [&](uint16_t label) {
    return grid_model ? particles_with_label(*grid_model, grid.label, label) : nodes_with_label(*tetmesh, label);
  });
  fix_particles(state, fixed_ids);
  report.fixed = static_cast<int64_t>(fixed_ids.size());

  // The surface and its coupling.
  SurfaceMesh surface;
  std::vector<float> lps_rest_vertices;
  SurfaceCoupling coupling;
  std::vector<uint32_t> triangles;
  const bool has_surface = !s.surface.empty();
  if (has_surface) {
    surface = read_surface_mesh_file(s.surface);
    lps_rest_vertices = surface.vertices;
    surface.lattice.origin -= shift;
    for (size_t i = 0; i < surface.vertices.size(); ++i) {
      surface.vertices[i] = static_cast<float>(static_cast<double>(surface.vertices[i]) - origin[i % 3]);
    }
    if (grid_model) {
      coupling = couple_surface(surface, grid_model->lattice, grid_model->cells, s.coupling);
    } else {
      TetEmbeddingStats st;
      coupling = embed_surface_in_tets(surface.vertices, *tetmesh, 10.0, &st);
      report.notes.push_back("surface: " + std::to_string(st.inside) + " vertices inside tets, " + std::to_string(st.outside) +
                             " outside (at most " + std::to_string(st.max_outside_mm) + " mm)");
    }
    triangles = surface.triangles;
  }

  // Step.
  const CriticalStep crit = std::visit([&](const auto& m) { return critical_time_step(m, s.safety_factor); }, model);
  report.critical_dt_s = crit.critical;
  double dt = s.dt_s > 0 ? s.dt_s : crit.dt;
  if (s.dt_s > 0 && s.dt_s > crit.critical) {
    report.notes.push_back("warning: dt_s " + std::to_string(s.dt_s) + " s is above the critical step " +
                           std::to_string(crit.critical) + " s; expect the stability guard to stop the run");
  } else if (s.dt_s == 0) {
    report.notes.push_back("auto step " + std::to_string(dt) + " s (" + std::to_string(s.safety_factor) + " x critical " +
                           std::to_string(crit.critical) + " s)");
  }

  // Tools.
  std::vector<ToolState> tools;
  for (const auto& t : s.tools) {
    ToolState ts;
    ts.spec = &t;
    std::string note;
    ts.path = resolve_path(t, bounds, rest, origin, &note);
    if (!note.empty()) report.notes.push_back(note);
    tools.push_back(std::move(ts));
  }
  std::vector<std::string> sphere_kinds;
  int64_t blade_tools = 0;
  for (const auto& t : s.tools) {
    if (t.kind == ToolAction::Kind::cut) {
      ++blade_tools;
    } else {
      sphere_kinds.push_back(to_string(t.kind));
    }
  }

  // Output frames.
  const int64_t frame_count = static_cast<int64_t>(std::floor(s.duration_s / s.frame_interval_s + 1e-9)) + 1;
  const int64_t nv = has_surface ? surface.vertex_count() : 0;
  const int64_t np = state.count();
  check_allocation(static_cast<uint64_t>(frame_count),
                   static_cast<uint64_t>(12 * nv + (s.write_particles ? 12 * np : 0) + 64), sfile, "output.frame_interval_s");
  Trajectory traj;
  traj.scenario = s.name;
  traj.model = s.model == ModelKind::spring_grid ? "spring_grid"
               : s.springs_from == SpringSource::grid ? "explicit_springs (grid)"
                                                      : "explicit_springs (tetmesh)";
  if (has_surface) {
    traj.surface_file = s.surface.string();
    traj.surface_sha256 = sha256_file(s.surface);
    traj.rest_vertices = lps_rest_vertices;
  } else {
    // No surface: the particles stand in for it as a point set (no triangles).
    traj.rest_vertices.resize(rest.size());
    for (size_t i = 0; i < rest.size(); ++i) traj.rest_vertices[i] = static_cast<float>(rest[i] + origin[i % 3]);
  }
  if (s.write_particles) {
    traj.rest_particles.resize(rest.size());
    for (size_t i = 0; i < rest.size(); ++i) traj.rest_particles[i] = static_cast<float>(rest[i] + origin[i % 3]);
  }
  const std::vector<float>& local_rest_vertices = has_surface ? surface.vertices : traj.rest_vertices;
  std::vector<TrajectoryMetric> metrics = {{"kinetic_energy", "nJ", {}},  {"elastic_energy", "nJ", {}},
                                           {"max_displacement", "mm", {}}, {"surface_max_displacement", "mm", {}},
                                           {"enclosed_volume", "mm^3", {}}, {"surface_area", "mm^2", {}},
                                           {"springs_cut", "1", {}},
                                           {"dt", "s", {}}};
  std::vector<float> vertices;
  int64_t springs_cut = 0, triangles_removed = 0, steps = 0;

  const auto record_frame = [&](double t) {
    if (has_surface) {
      move_surface(coupling, state, rest, vertices, Backend::cpu, s.threads);
    } else {
      vertices.resize(static_cast<size_t>(3 * np));
      for (int64_t i = 0; i < np; ++i) {
        vertices[static_cast<size_t>(3 * i)] = state.x[static_cast<size_t>(i)];
        vertices[static_cast<size_t>(3 * i + 1)] = state.y[static_cast<size_t>(i)];
        vertices[static_cast<size_t>(3 * i + 2)] = state.z[static_cast<size_t>(i)];
      }
    }
    traj.time.push_back(t);
    for (size_t i = 0; i < vertices.size(); ++i) traj.vertices.push_back(static_cast<float>(vertices[i] + origin[i % 3]));
    if (traj.topologies.empty() || traj.topologies.back() != triangles) traj.topologies.push_back(triangles);
    traj.topology_of_frame.push_back(static_cast<int32_t>(traj.topologies.size() - 1));
    if (s.write_particles) {
      for (int64_t i = 0; i < np; ++i) {
        traj.particles.push_back(static_cast<float>(state.x[static_cast<size_t>(i)] + origin[0]));
        traj.particles.push_back(static_cast<float>(state.y[static_cast<size_t>(i)] + origin[1]));
        traj.particles.push_back(static_cast<float>(state.z[static_cast<size_t>(i)] + origin[2]));
      }
    }
    double max_disp = 0, surf_disp = 0;
    for (int64_t i = 0; i < np; ++i) {
      const double d = std::pow(state.x[static_cast<size_t>(i)] - rest[static_cast<size_t>(3 * i)], 2) +
                       std::pow(state.y[static_cast<size_t>(i)] - rest[static_cast<size_t>(3 * i + 1)], 2) +
                       std::pow(state.z[static_cast<size_t>(i)] - rest[static_cast<size_t>(3 * i + 2)], 2);
      max_disp = std::max(max_disp, d);
    }
    for (size_t i = 0; i < vertices.size(); i += 3) {
      double d = 0;
      for (size_t c = 0; c < 3; ++c) d += std::pow(double(vertices[i + c]) - local_rest_vertices[i + c], 2);
      surf_disp = std::max(surf_disp, d);
    }
    metrics[0].values.push_back(kinetic_energy(state, dt));
    metrics[1].values.push_back(std::visit([&](const auto& m) { return spring_energy(m, state); }, model));
    metrics[2].values.push_back(std::sqrt(max_disp));
    metrics[3].values.push_back(std::sqrt(surf_disp));
    metrics[4].values.push_back(has_surface ? enclosed_volume(vertices, triangles) : 0.0);
    metrics[5].values.push_back(has_surface ? surface_area(vertices, triangles) : 0.0);
    metrics[6].values.push_back(static_cast<double>(springs_cut));
    metrics[7].values.push_back(dt);
    for (const auto& ts : tools) {
      if (ts.spec->kind == ToolAction::Kind::cut) continue;
      const Vec3 l = ts.path.at(t), c{l[0] + origin[0], l[1] + origin[1], l[2] + origin[2]};
      const bool on = ts.active(t) && (ts.spec->kind == ToolAction::Kind::probe || ts.grab.has_value() || !ts.loaded.empty());
      traj.spheres.insert(traj.spheres.end(), {c[0], c[1], c[2], on ? ts.spec->radius_mm : 0.0});
    }
    for (const auto& ts : tools) {
      if (ts.spec->kind != ToolAction::Kind::cut) continue;
      const Vec3 l = ts.path.at(t), c{l[0] + origin[0], l[1] + origin[1], l[2] + origin[2]};
      const auto& e = ts.spec->blade_edge_mm;
      traj.blades.insert(traj.blades.end(), {c[0] - e[0] / 2, c[1] - e[1] / 2, c[2] - e[2] / 2, c[0] + e[0] / 2,
                                             c[1] + e[1] / 2, c[2] + e[2] / 2, ts.active(t) ? 1.0 : 0.0});
    }
  };
  const auto truncate_frames = [&](size_t frames) {
    traj.time.resize(frames);
    traj.vertices.resize(frames * static_cast<size_t>(traj.vertex_count()) * 3);
    traj.topology_of_frame.resize(frames);
    traj.topologies.resize(frames ? static_cast<size_t>(traj.topology_of_frame.back()) + 1 : 0);
    traj.particles.resize(frames * traj.rest_particles.size());
    for (auto& m : metrics) m.values.resize(frames);
    traj.spheres.resize(frames * sphere_kinds.size() * 4);
    traj.blades.resize(frames * static_cast<size_t>(blade_tools) * 7);
  };

  StabilityGuardOptions guard_options;
  guard_options.gravity = std::sqrt(s.gravity[0] * s.gravity[0] + s.gravity[1] * s.gravity[1] + s.gravity[2] * s.gravity[2]);
  StabilityGuard guard = std::visit([&](const auto& m) { return make_stability_guard(m, dt, guard_options); }, model);
  StepParameters params;
  params.dt = dt;
  params.damping = std::min(0.99, s.damping_per_s * dt);
  params.gravity = s.gravity;
  params.threads = s.threads;

  // Where the state is stepped. On a CUDA device (docs/gpu.md) the run takes no force tool (a force
  // changes the state on the host every step), and restarts after instability are not offered.
  std::unique_ptr<SpringEngine> engine;
  if (backend == Backend::cuda) {
    for (const auto& t : s.tools) {
      if (t.kind == ToolAction::Kind::force) {
        throw InputError(sfile, t.label, "force tools run on the cpu backend only; set backend: cpu");
      }
    }
    engine = std::make_unique<DeviceSpringEngine>(model, state);
    report.notes.push_back("backend cuda: " + cuda_device_info(0).name);
  } else {
    engine = std::make_unique<HostSpringEngine>(model, state, s.threads);
  }

  // Cuts the springs and the surface crossing the quad swept by the blade's edge from centre c0 to c1.
  const double shortest_spring = std::visit([](const auto& m) -> double {
    if constexpr (std::is_same_v<std::decay_t<decltype(m)>, SpringGridModel>) {
      return *std::min_element(m.rest_length.begin(), m.rest_length.end());
    } else {
      return m.rest_length.empty() ? 1.0 : static_cast<double>(*std::min_element(m.rest_length.begin(), m.rest_length.end()));
    }
  }, model);
  const auto sweep_blade = [&](const ToolAction& spec, const Vec3& c0, const Vec3& c1) {
    const auto& e = spec.blade_edge_mm;
    const Vec3 a0{c0[0] - e[0] / 2, c0[1] - e[1] / 2, c0[2] - e[2] / 2}, b0{c0[0] + e[0] / 2, c0[1] + e[1] / 2, c0[2] + e[2] / 2};
    const Vec3 a1{c1[0] - e[0] / 2, c1[1] - e[1] / 2, c1[2] - e[2] / 2}, b1{c1[0] + e[0] / 2, c1[1] + e[1] / 2, c1[2] + e[2] / 2};
    engine->to_host();
    if (has_surface) move_surface(coupling, state, rest, vertices, Backend::cpu, s.threads);
    for (const Triangle& tri : {Triangle{a0, b0, b1}, Triangle{a0, b1, a1}}) {
      if (has_surface) triangles_removed += cut_surface(triangles, coupling, vertices, state, tri).triangles_removed;
      springs_cut += engine->cut(tri);
    }
  };

  double t = 0;
  record_frame(0.0);
  int64_t next_frame = 1;
  // The last frame's state, for restarts with half the step; kept only when the run may restart.
  const bool restartable = s.max_step_halvings > 0 && !engine->on_device();
  Checkpoint checkpoint;
  if (restartable) checkpoint = Checkpoint{state, model, tools, triangles, coupling, 0.0, 0, 0, 0, 1};
  int halvings = 0;
  const auto start = std::chrono::steady_clock::now();
  double last_progress = -1;
  bool tool_work = false;  // a tool acted since the last stability check
  while (next_frame < frame_count) {
    const double t_next = t + dt;
    engine->step(params);
    ++steps;
    for (auto& ts : tools) {
      const ToolAction& spec = *ts.spec;
      const Vec3 c = ts.path.at(t_next);
      if (spec.kind == ToolAction::Kind::grab) {
        if (!ts.grab && !ts.released && ts.active(t_next)) {
          ts.grab = engine->capture({c, spec.radius_mm}, true, &ts.grab_handle);
          if (ts.grab->particles.empty()) {
            throw InputError(sfile, spec.label, "grabs no particle at t = " + std::to_string(t_next) + " s (sphere of radius " +
                                                    std::to_string(spec.radius_mm) + " mm at (" + std::to_string(c[0] + origin[0]) + ", " +
                                                    std::to_string(c[1] + origin[1]) + ", " + std::to_string(c[2] + origin[2]) +
                                                    ") LPS mm); move it onto the tissue or set snap_to_tissue: true");
          }
          report.notes.push_back(spec.label + ": grabbed " + std::to_string(ts.grab->particles.size()) + " particles at t = " +
                                 std::to_string(t_next) + " s");
        }
        if (ts.grab && !ts.active(t_next)) {
          ts.grab.reset();
          engine->release_grab(ts.grab_handle);
          ts.released = true;
          tool_work = true;  // the release turns the stretch into motion
        }
        if (ts.grab) {
          engine->apply_grab(*ts.grab, ts.grab_handle, c);
          tool_work = true;
        }
      } else if (spec.kind == ToolAction::Kind::force) {
        // An external force F shared by n free particles adds (F / n) / m dt^2 to each one's Verlet
        // update: applied after the step, as the papers apply the tools, it is the same update as a
        // force inside the step (x_next = ... + (f + F / n) / m dt^2).
        if (ts.loaded.empty() && !ts.released && ts.active(t_next)) {
          const Grab inside = engine->capture({c, spec.radius_mm}, false, nullptr);
          for (const int32_t i : inside.particles) {
            if (state.inv_mass[static_cast<size_t>(i)] > 0) ts.loaded.push_back(i);
          }
          if (ts.loaded.empty()) {
            throw InputError(sfile, spec.label, "the force's sphere holds no free particle at t = " + std::to_string(t_next) +
                                                    " s; move it onto the tissue or set snap_to_tissue: true");
          }
          report.notes.push_back(spec.label + ": force shared by " + std::to_string(ts.loaded.size()) + " particles");
        }
        if (!ts.loaded.empty() && !ts.active(t_next)) {
          ts.loaded.clear();
          ts.released = true;
          tool_work = true;
        }
        const double n = static_cast<double>(ts.loaded.size());
        for (const int32_t i : ts.loaded) {
          const size_t k = static_cast<size_t>(i);
          const double a = 1e6 / n * state.inv_mass[k] * dt * dt;  // N -> uN = g mm/s^2
          state.x[k] += static_cast<Real>(spec.force_n[0] * a);
          state.y[k] += static_cast<Real>(spec.force_n[1] * a);
          state.z[k] += static_cast<Real>(spec.force_n[2] * a);
        }
        tool_work |= !ts.loaded.empty();
      } else if (spec.kind == ToolAction::Kind::probe) {
        if (ts.active(t_next)) tool_work |= engine->probe({c, spec.radius_mm}) > 0;
      } else {
        // The blade cuts what its edge swept since the last sweep (from ts.cut_from to now), once it has
        // moved a quarter of the shortest spring or reaches a keyframe or its end: each sweep then lies
        // on one straight segment of the path, a planar quad (two triangles), and a spring cannot slip
        // between two sweeps. Sweeping every step would cost a pass over the model per step.
        if (!ts.cut_from) {
          if (ts.active(t_next)) ts.cut_from = std::max(spec.start_s, t);
        }
        while (ts.cut_from) {
          const double from = *ts.cut_from, to_end = std::min(t_next, spec.end_s);
          double to = to_end;
          for (const double kt : ts.path.t) {
            if (kt > from && kt < to) to = kt;
          }
          const Vec3 c0 = ts.path.at(from), c1 = ts.path.at(to);
          const double moved = std::sqrt(std::pow(c1[0] - c0[0], 2) + std::pow(c1[1] - c0[1], 2) + std::pow(c1[2] - c0[2], 2));
          const bool at_end = t_next >= spec.end_s;
          if (moved < 0.25 * shortest_spring && to == to_end && !at_end) break;
          sweep_blade(spec, c0, c1);
          tool_work = true;
          ts.cut_from = to;
          if (to == to_end) {
            if (at_end) ts.cut_from.reset();
            break;
          }
        }
      }
    }
    t = t_next;
    const double frame_time = static_cast<double>(next_frame) * s.frame_interval_s;
    const bool frame_due = t >= frame_time - 0.5 * dt;
    if (frame_due || steps % 1000 == 0) {
      engine->to_host();
      const StabilityReport check = guard.check(state, t, tool_work);
      tool_work = false;
      if (!check.stable) {
        if (!restartable || halvings >= s.max_step_halvings) {
          throw RuntimeError(sfile + ": the run became unstable: " + check.message +
                             (s.max_step_halvings > 0 ? " (after " + std::to_string(halvings) + " step halvings)"
                                                      : " Set time.dt_s lower, or allow time.max_step_halvings."));
        }
        // Restart from the last frame with half the step. Verlet's previous positions are rescaled so
        // the velocities stay the same: x_prev = x - (x - x_prev) / 2.
        state = checkpoint.state;
        model = checkpoint.model;
        tools = checkpoint.tools;
        triangles = checkpoint.triangles;
        coupling = checkpoint.coupling;
        t = checkpoint.t;
        steps = checkpoint.steps;
        springs_cut = checkpoint.springs_cut;
        triangles_removed = checkpoint.triangles_removed;
        truncate_frames(checkpoint.frames);
        next_frame = static_cast<int64_t>(checkpoint.frames);
        for (int32_t i = 0; i < state.count(); ++i) {
          const size_t k = static_cast<size_t>(i);
          state.px[k] = state.x[k] - (state.x[k] - state.px[k]) / 2;
          state.py[k] = state.y[k] - (state.y[k] - state.py[k]) / 2;
          state.pz[k] = state.z[k] - (state.z[k] - state.pz[k]) / 2;
        }
        dt /= 2;
        params.dt = dt;
        params.damping = std::min(0.99, s.damping_per_s * dt);
        guard = std::visit([&](const auto& m) { return make_stability_guard(m, dt, guard_options); }, model);
        ++halvings;
        tool_work = true;  // the restart changes the energy the guard last saw
        report.notes.push_back("unstable at t = " + std::to_string(check.time) + " s: restarted from t = " + std::to_string(t) +
                               " s with dt = " + std::to_string(dt) + " s (" + check.message + ")");
        continue;
      }
    }
    if (frame_due) {
      record_frame(t);
      ++next_frame;
      if (restartable) {
        checkpoint = Checkpoint{state, model, tools, triangles, coupling, t, steps, springs_cut, triangles_removed, traj.time.size()};
      }
      const double fraction = t / s.duration_s;
      if (progress && fraction - last_progress >= 0.01) {
        progress(fraction);
        last_progress = fraction;
      }
    }
  }
  report.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  report.dt_s = dt;
  report.halvings = halvings;
  report.steps = steps;
  report.springs_cut = springs_cut;
  report.surface_triangles_removed = triangles_removed;
  traj.dt_s = dt;
  traj.metrics = std::move(metrics);
  traj.sphere_kinds = sphere_kinds;
  if (progress) progress(1.0);
  if (report_out) *report_out = std::move(report);
  return traj;
}

}  // namespace ctsurg::sim
