#include "ctsurg/sim/scenario/trajectory_recorder.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/file_hash.h"
#include "ctsurg/core/memory_guard.h"
#include "ctsurg/sim/scenario/scenario_model.h"
#include "ctsurg/sim/surface/surface_measures.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

namespace ctsurg::sim {

TrajectoryRecorder::TrajectoryRecorder(const Scenario& s, const SimulationEngine& engine, const ToolTimeline& timeline,
                                       std::vector<float> surface_lps_vertices, int64_t frames)
    : origin_(engine.origin()), write_particles_(s.write_particles), tools_(timeline.size()) {
  const std::vector<double>& rest = engine.rest_positions();
  const int64_t np = static_cast<int64_t>(rest.size() / 3);
  const int64_t nv = engine.has_surface() ? static_cast<int64_t>(surface_lps_vertices.size() / 3) : np;
  check_allocation(static_cast<uint64_t>(frames), static_cast<uint64_t>(12 * nv + (s.write_particles ? 12 * np : 0) + 64),
                   s.file.string(), "output.frame_interval_s");
  traj_.scenario = s.name;
  traj_.model = model_label(s);
  if (engine.has_surface()) {
    // A surface the engine draws itself (a vessel's, from its atoms) has no file: the trajectory's own
    // triangles, which ctsurg-render draws without --surface. Only a scenario's surface file is named.
    if (!s.surface.empty()) {
      traj_.surface_file = s.surface.string();
      traj_.surface_sha256 = sha256_file(s.surface);
    }
    traj_.rest_vertices = std::move(surface_lps_vertices);
  } else {
    // No surface: the nodes stand in for it as a point set (no triangles).
    traj_.rest_vertices.resize(rest.size());
    for (size_t i = 0; i < rest.size(); ++i) traj_.rest_vertices[i] = static_cast<float>(rest[i] + origin_[i % 3]);
  }
  if (s.write_particles) {
    traj_.rest_particles.resize(rest.size());
    for (size_t i = 0; i < rest.size(); ++i) traj_.rest_particles[i] = static_cast<float>(rest[i] + origin_[i % 3]);
    traj_.element_nodes = engine.elements(traj_.elements);  // the FE mesh over the particles (none: 0)
  }
  metrics_ = {{"kinetic_energy", "nJ", {}},          {"elastic_energy", "nJ", {}},   {"max_displacement", "mm", {}},
              {"surface_max_displacement", "mm", {}}, {"enclosed_volume", "mm^3", {}}, {"surface_area", "mm^2", {}},
              {"springs_cut", "1", {}},               {"dt", "s", {}}};
  for (const auto& [name, units] : engine.extra_metrics()) metrics_.push_back({name, units, {}});
  for (size_t i = 0; i < timeline.size(); ++i) {
    const ToolType& type = *timeline.tool(i).type;
    switch (type.record) {
      case ToolRecord::blade:
        ++blades_;
        break;
      case ToolRecord::stitches:
        stitches_ += timeline.stitch_points(i).size();
        break;
      case ToolRecord::instrument: {
        const Instrument& shape = *timeline.instrument(i);
        TrajectoryInstrument ins;
        ins.name = timeline.tool(i).instrument_mesh.string();
        ins.vertices.assign(shape.mesh.vertices.begin(), shape.mesh.vertices.end());
        ins.triangles = shape.mesh.faces;
        traj_.instruments.push_back(std::move(ins));
        break;
      }
      case ToolRecord::sphere:
        traj_.sphere_kinds.push_back(type.record_name);
        break;
    }
    // A run with a tool that removes tissue records how much (the only runs that have the metric).
    removal_ = removal_ || type.acts == ToolPrimitive::remove;
  }
  if (removal_) metrics_.push_back({"removed_volume", "mm^3", {}});
}

namespace {

// A sphere that holds or loads what it captured shows while it holds something; the others (a probe,
// a cautery's tip) while their window is open.
bool sphere_shows_engagement(const ToolType& type) { return type.acts == ToolPrimitive::hold || type.acts == ToolPrimitive::load; }

}  // namespace

void TrajectoryRecorder::record(SimulationEngine& engine, const ToolTimeline& timeline, double t) {
  engine.surface_vertices(vertices_);
  traj_.time.push_back(t);
  for (size_t i = 0; i < vertices_.size(); ++i) traj_.vertices.push_back(static_cast<float>(vertices_[i] + origin_[i % 3]));
  const std::vector<uint32_t>& triangles = engine.triangles();
  if (traj_.topologies.empty() || traj_.topologies.back() != triangles) {
    traj_.topologies.push_back(triangles);
    closing_.push_back(engine.closing_triangles());
  }
  traj_.topology_of_frame.push_back(static_cast<int32_t>(traj_.topologies.size() - 1));
  // The local region (an FEM run with one): (F, V) once any frame has it, 0 for the frames before.
  const size_t nv = static_cast<size_t>(traj_.vertex_count()), frame = traj_.time.size() - 1;
  if (engine.surface_vertex_region(region_)) {
    if (region_.size() != nv) {
      throw RuntimeError("trajectory recorder: the engine gave " + std::to_string(region_.size()) + " region flags for " +
                         std::to_string(nv) + " surface vertices");
    }
    if (traj_.vertex_region.empty()) traj_.vertex_region.assign(frame * nv, 0);
    traj_.vertex_region.insert(traj_.vertex_region.end(), region_.begin(), region_.end());
  } else if (!traj_.vertex_region.empty()) {
    traj_.vertex_region.resize(traj_.vertex_region.size() + nv, 0);
  }
  if (write_particles_) {
    engine.positions(positions_);
    for (size_t i = 0; i < positions_.size(); ++i) traj_.particles.push_back(static_cast<float>(positions_[i] + origin_[i % 3]));
  }
  const EngineMetrics m = engine.metrics();
  double surface_disp = m.max_displacement;
  if (engine.has_surface()) {
    const std::vector<Real>& rest = engine.surface_rest_vertices();
    double worst = 0;
    for (size_t i = 0; i < vertices_.size(); i += 3) {
      double d = 0;
      for (size_t c = 0; c < 3; ++c) d += std::pow(double(vertices_[i + c]) - rest[i + c], 2);
      worst = std::max(worst, d);
    }
    surface_disp = std::sqrt(worst);
  }
  const bool surface = engine.has_surface();
  const double values[] = {m.kinetic_energy,
                           m.elastic_energy,
                           m.max_displacement,
                           surface_disp,
                           surface ? enclosed_volume(vertices_, triangles) : 0.0,
                           surface ? surface_area(vertices_, triangles) : 0.0,
                           static_cast<double>(m.springs_cut),
                           engine.dt()};
  if (std::size(values) + m.extra.size() + (removal_ ? 1 : 0) != metrics_.size()) {
    throw RuntimeError("trajectory recorder: the engine gave " + std::to_string(m.extra.size()) + " extra metrics, it named " +
                       std::to_string(metrics_.size() - std::size(values)));
  }
  for (size_t k = 0; k < std::size(values); ++k) metrics_[k].values.push_back(values[k]);
  for (size_t k = 0; k < m.extra.size(); ++k) metrics_[std::size(values) + k].values.push_back(m.extra[k]);
  if (removal_) metrics_.back().values.push_back(m.removed_volume);
  for (size_t i = 0; i < timeline.size(); ++i) {
    const ToolAction& tool = timeline.tool(i);
    if (tool.type->record == ToolRecord::blade || tool.type->record == ToolRecord::stitches) continue;
    const Vec3 l = timeline.position(i, t), c{l[0] + origin_[0], l[1] + origin_[1], l[2] + origin_[2]};
    if (tool.type->record == ToolRecord::instrument) {
      const Quaternion q = timeline.orientation(i, t);
      traj_.instrument_poses.insert(traj_.instrument_poses.end(),
                                    {timeline.active(i, t) ? 1.0 : 0.0, q[0], q[1], q[2], q[3], c[0], c[1], c[2]});
      continue;
    }
    const bool on = timeline.active(i, t) && (!sphere_shows_engagement(*tool.type) || engine.engaged(i));
    traj_.spheres.insert(traj_.spheres.end(), {c[0], c[1], c[2], on ? tool.radius_mm : 0.0});
    std::array<double, 6> load{};
    const bool measured = engine.tool_load(i, load);
    loads_.push_back(measured ? 1.0 : 0.0);
    for (const double v : load) loads_.push_back(measured ? v : 0.0);
    any_load_ = any_load_ || measured;
  }
  for (size_t i = 0; i < timeline.size(); ++i) {
    const ToolAction& tool = timeline.tool(i);
    if (tool.type->record != ToolRecord::blade) continue;
    const Vec3 l = timeline.position(i, t), c{l[0] + origin_[0], l[1] + origin_[1], l[2] + origin_[2]};
    const auto& e = tool.blade_edge_mm;
    traj_.blades.insert(traj_.blades.end(), {c[0] - e[0] / 2, c[1] - e[1] / 2, c[2] - e[2] / 2, c[0] + e[0] / 2,
                                             c[1] + e[1] / 2, c[2] + e[2] / 2, timeline.active(i, t) ? 1.0 : 0.0});
  }
  // Stitches: where the engine holds them once placed, else where the scenario puts them (not placed).
  for (size_t i = 0; i < timeline.size(); ++i) {
    if (timeline.tool(i).type->record != ToolRecord::stitches) continue;
    const std::vector<std::array<Vec3, 2>> placed = engine.stitches(i);
    const std::vector<std::array<Vec3, 2>>& given = timeline.stitch_points(i);
    const bool on = placed.size() == given.size();
    for (size_t k = 0; k < given.size(); ++k) {
      const auto& ends = on ? placed[k] : given[k];
      for (const Vec3& p : ends) traj_.stitches.insert(traj_.stitches.end(), {p[0] + origin_[0], p[1] + origin_[1], p[2] + origin_[2]});
      traj_.stitches.push_back(on ? 1.0 : 0.0);
    }
  }
}

double TrajectoryRecorder::last_metric(std::string_view name) const {
  for (const TrajectoryMetric& m : metrics_)
    if (m.name == name) return m.values.empty() ? NAN : m.values.back();
  return NAN;
}

void TrajectoryRecorder::truncate(size_t frames) {
  if (frames >= traj_.time.size()) return;
  traj_.time.resize(frames);
  traj_.vertices.resize(frames * static_cast<size_t>(traj_.vertex_count()) * 3);
  traj_.topology_of_frame.resize(frames);
  traj_.topologies.resize(frames ? static_cast<size_t>(traj_.topology_of_frame.back()) + 1 : 0);
  closing_.resize(traj_.topologies.size());
  traj_.particles.resize(frames * traj_.rest_particles.size());
  if (!traj_.vertex_region.empty()) traj_.vertex_region.resize(frames * static_cast<size_t>(traj_.vertex_count()));
  for (auto& m : metrics_) m.values.resize(frames);
  traj_.spheres.resize(frames * traj_.sphere_kinds.size() * 4);
  loads_.resize(frames * traj_.sphere_kinds.size() * 7);
  traj_.blades.resize(frames * blades_ * 7);
  traj_.instrument_poses.resize(frames * traj_.instruments.size() * 8);
  traj_.stitches.resize(frames * stitches_ * 7);
}

void TrajectoryRecorder::add_tool(const ToolTimeline& timeline, size_t i) {
  if (i != tools_ || i >= timeline.size()) {
    throw RuntimeError("trajectory recorder: tool " + std::to_string(i) + " added out of order (next: " + std::to_string(tools_) + ")");
  }
  const ToolAction& tool = timeline.tool(i);
  const bool blade = tool.type->record == ToolRecord::blade;
  if (!blade && tool.type->record != ToolRecord::sphere) {
    throw RuntimeError("trajectory recorder: " + tool.label + " cannot be added while running");
  }
  const size_t frames = traj_.time.size(), width = blade ? 7 : 4, tools = blade ? blades_ : traj_.sphere_kinds.size();
  std::vector<double>& data = blade ? traj_.blades : traj_.spheres;
  std::vector<double> grown, loads;  // loads: a sphere's rows of loads_ (7 each), none measured before it acts
  grown.reserve(frames * (tools + 1) * width);
  if (!blade) loads.reserve(frames * (tools + 1) * 7);
  for (size_t f = 0; f < frames; ++f) {
    const double t = traj_.time[f];
    if (timeline.active(i, t)) throw RuntimeError("trajectory recorder: " + tool.label + " was added after it started");
    grown.insert(grown.end(), data.begin() + static_cast<std::ptrdiff_t>(f * tools * width),
                 data.begin() + static_cast<std::ptrdiff_t>((f + 1) * tools * width));
    const Vec3 l = timeline.position(i, t), c{l[0] + origin_[0], l[1] + origin_[1], l[2] + origin_[2]};
    if (blade) {
      const auto& e = tool.blade_edge_mm;
      grown.insert(grown.end(), {c[0] - e[0] / 2, c[1] - e[1] / 2, c[2] - e[2] / 2, c[0] + e[0] / 2, c[1] + e[1] / 2, c[2] + e[2] / 2, 0.0});
    } else {
      grown.insert(grown.end(), {c[0], c[1], c[2], 0.0});
      loads.insert(loads.end(), loads_.begin() + static_cast<std::ptrdiff_t>(f * tools * 7),
                   loads_.begin() + static_cast<std::ptrdiff_t>((f + 1) * tools * 7));
      loads.insert(loads.end(), 7, 0.0);
    }
  }
  data = std::move(grown);
  if (!blade) loads_ = std::move(loads);
  ++tools_;
  if (blade) {
    ++blades_;
  } else {
    traj_.sphere_kinds.push_back(tool.type->record_name);
  }
}

void TrajectoryRecorder::finish_into(Trajectory& traj, double dt) const {
  traj.dt_s = dt;
  traj.metrics = metrics_;
  if (any_load_) traj.sphere_loads = loads_;  // only a run whose engine measured a tool's load says so
  // Only a run that closed some hole says so (older readers and runs without cuts see no dataset).
  if (std::any_of(closing_.begin(), closing_.end(), [](int64_t n) { return n > 0; })) traj.closing_triangles = closing_;
}

Trajectory TrajectoryRecorder::snapshot(double dt) const {
  Trajectory traj = traj_;
  finish_into(traj, dt);
  return traj;
}

Trajectory TrajectoryRecorder::finish(double dt) {
  finish_into(traj_, dt);
  metrics_.clear();
  return std::move(traj_);
}

}  // namespace ctsurg::sim
