#include "ctsurg/sim/vessel/vessel_engine.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/base/kernels/segment_triangle_impl.h"
#include "ctsurg/sim/base/tool_shapes.h"
#include "vessel_math.h"

#include <algorithm>
#include <cmath>

namespace ctsurg::sim {
namespace {

V3 eig(const Vec3& v) { return {v[0], v[1], v[2]}; }

std::string vessel_lps_text(const Vec3& local, const Vec3& origin) {
  char text[96];
  std::snprintf(text, sizeof text, "(%.1f, %.1f, %.1f) mm LPS", local[0] + origin[0], local[1] + origin[1], local[2] + origin[2]);
  return text;
}

}  // namespace

VesselEngine::VesselEngine(VesselChain chain, const std::vector<int32_t>& fixed_atoms, const Vec3& origin, const VesselEngineOptions& options,
                           Backend backend)
    : chain_(std::make_unique<VesselChain>(std::move(chain))), origin_(origin), options_(options) {
  if (backend != Backend::cpu) {
    throw InputError(options.where, "backend", "the vessel model runs on the cpu only (its sparse direct solve has no device "
                                               "version); set backend: cpu");
  }
  if (!(options.dt >= 0) || !(options.mass_damping >= 0)) throw InputError(options.where, "time", "needs dt >= 0 and damping >= 0");
  VesselDynamicsOptions d;
  d.dt = options.dt > 0 ? options.dt : 1.0 / 60;
  d.mass_damping = options.mass_damping;
  d.gravity = options.gravity;
  d.max_newton_iterations = options.max_newton_iterations;
  dynamics_ = std::make_unique<VesselDynamics>(*chain_, d);
  dynamics_->fix_atoms(fixed_atoms);
  skin_ = std::make_unique<VesselSkin>(*chain_, options.spokes, options.skinning);
  alive_.assign(static_cast<size_t>(chain_->segment_count()), 1);
  std::vector<float> rest;
  skin_->vertices(chain_->rest, options.skinning == VesselSkinning::rmf ? &chain_->segment_rest_frame : nullptr, rest);
  rest_surface_.assign(rest.begin(), rest.end());
  double shortest = 1e300;
  for (const double l : chain_->segment_length) shortest = std::min(shortest, l);
  blade_sweep_ = 0.5 * shortest;
  counts_.nodes = chain_->atom_count();
  for (int32_t a = 0; a < chain_->atom_count(); ++a) counts_.fixed += dynamics_->atom_fixed(a) ? 1 : 0;
  counts_.springs = chain_->segment_count() + static_cast<int64_t>(chain_->joints.size());
  counts_.critical_dt_s = 0;  // implicit: no critical step
  save_checkpoint();
}

void VesselEngine::note(const std::string& text) const {
  if (options_.note) options_.note(text);
}

std::vector<std::pair<std::string, std::string>> VesselEngine::extra_metrics() const {
  return {{"chain_length", "mm"}, {"max_strain", "1"}, {"newton_iterations", "1"}};
}

std::vector<int32_t> VesselEngine::atoms_in_sphere(const Vec3& centre, double radius, bool free_only) const {
  std::vector<int32_t> ids;
  const V3 c = eig(centre);
  for (int32_t a = 0; a < chain_->atom_count(); ++a) {
    if (free_only && dynamics_->atom_fixed(a)) continue;
    if ((at(dynamics_->x, static_cast<size_t>(a)) - c).norm() <= radius) ids.push_back(a);
  }
  return ids;
}

void VesselEngine::apply_tools(const std::vector<ToolInput>& tools) {
  if (holds_.size() < tools.size()) holds_.resize(tools.size());
  VesselDynamics& d = *dynamics_;
  d.clear_prescribed();
  std::fill(d.force.begin(), d.force.end(), 0.0);
  bool topology = false;
  for (size_t i = 0; i < tools.size(); ++i) {
    const ToolInput& tool = tools[i];
    Hold& h = holds_[i];
    switch (tool.acts) {
      case ToolPrimitive::hold: {
        if (h.atoms.empty() && !h.released && tool.active) {
          h.atoms = atoms_in_sphere(tool.centre, tool.radius_mm, true);
          if (h.atoms.empty()) {
            throw InputError(options_.where, tool.label,
                             "captures no atom of the vessel at t = " + std::to_string(time_) + " s (sphere of radius " +
                                 std::to_string(tool.radius_mm) + " mm at " + vessel_lps_text(tool.centre, origin_) +
                                 "; the atoms are on the centerline, fixed ones are not grabbed): move it onto the "
                                 "centerline, make it larger or set snap_to_tissue: true");
          }
          std::vector<uint8_t> in(static_cast<size_t>(chain_->atom_count()), 0);
          for (const int32_t a : h.atoms) {
            in[static_cast<size_t>(a)] = 1;
            const V3 o = at(d.x, static_cast<size_t>(a)) - eig(tool.centre);
            h.offsets.insert(h.offsets.end(), {o.x(), o.y(), o.z()});
          }
          for (int32_t s = 0; s < chain_->segment_count(); ++s) {
            if (in[static_cast<size_t>(chain_->segment_atoms[2 * static_cast<size_t>(s)])] &&
                in[static_cast<size_t>(chain_->segment_atoms[2 * static_cast<size_t>(s) + 1])]) {
              h.segments.push_back(s);
              h.frames.push_back(d.q[static_cast<size_t>(s)]);
            }
          }
          h.orientation = tool.orientation;
          note(tool.label + ": grabbed " + std::to_string(h.atoms.size()) + " atoms at t = " + std::to_string(time_) + " s");
        }
        if (!h.atoms.empty() && !tool.active) {
          h.atoms.clear();
          h.offsets.clear();
          h.segments.clear();
          h.frames.clear();
          h.released = true;
        }
        if (!h.atoms.empty()) {
          const Q turn = (to_eigen(tool.orientation) * to_eigen(h.orientation).conjugate()).normalized();
          const M3 r = turn.toRotationMatrix();
          for (size_t k = 0; k < h.atoms.size(); ++k) {
            const V3 p = eig(tool.centre) + r * at(h.offsets, k);
            d.prescribe_atom(h.atoms[k], {p.x(), p.y(), p.z()});
          }
          for (size_t k = 0; k < h.segments.size(); ++k) {
            d.prescribe_segment(h.segments[k], to_quaternion((turn * to_eigen(h.frames[k])).normalized()));
          }
        }
        break;
      }
      case ToolPrimitive::load: {
        if (h.atoms.empty() && !h.released && tool.active) {
          h.atoms = atoms_in_sphere(tool.centre, tool.radius_mm, true);
          if (h.atoms.empty()) {
            throw InputError(options_.where, tool.label, "the force's sphere holds no free atom of the vessel at t = " +
                                                             std::to_string(time_) + " s (at " + vessel_lps_text(tool.centre, origin_) +
                                                             "); move it onto the centerline or set snap_to_tissue: true");
          }
          note(tool.label + ": force shared by " + std::to_string(h.atoms.size()) + " atoms");
        }
        if (!h.atoms.empty() && !tool.active) {
          h.atoms.clear();
          h.released = true;
        }
        const double share = h.atoms.empty() ? 0.0 : 1e6 / static_cast<double>(h.atoms.size());  // N -> uN
        for (const int32_t a : h.atoms)
          for (size_t c = 0; c < 3; ++c) d.force[3 * static_cast<size_t>(a) + c] += share * tool.force_n[c];
        break;
      }
      case ToolPrimitive::separate:
        topology |= cut(tool);
        break;
      case ToolPrimitive::push_sphere:
        break;  // after the step
      case ToolPrimitive::push_shape:
      case ToolPrimitive::stitch:
      case ToolPrimitive::remove:
        throw InputError(options_.where, tool.label, tool.name +
                                                         " is not supported by the vessel model (grab, clamp, force, probe and "
                                                         "cut are)");
    }
  }
  if (topology) skin_->update_topology(alive_);
}

bool VesselEngine::cut(const ToolInput& tool) {
  bool any = false;
  for (const auto& [from, to] : tool.sweeps) {
    for (const Triangle& t : swept_blade(from, to, tool.blade_edge_mm)) {
      const TriangleView view{{t.a[0], t.a[1], t.a[2]}, {t.b[0], t.b[1], t.b[2]}, {t.c[0], t.c[1], t.c[2]}};
      for (int32_t s = 0; s < chain_->segment_count(); ++s) {
        if (!alive_[static_cast<size_t>(s)]) continue;
        const double* p = &dynamics_->x[3 * static_cast<size_t>(chain_->segment_atoms[2 * static_cast<size_t>(s)])];
        const double* q = &dynamics_->x[3 * static_cast<size_t>(chain_->segment_atoms[2 * static_cast<size_t>(s) + 1])];
        if (!segment_crosses_triangle(p, q, view)) continue;
        alive_[static_cast<size_t>(s)] = 0;
        dynamics_->cut_segment(s);
        ++segments_cut_;
        any = true;
        note(tool.label + ": cut the vessel between atoms " + std::to_string(chain_->segment_atoms[2 * static_cast<size_t>(s)]) +
             " and " + std::to_string(chain_->segment_atoms[2 * static_cast<size_t>(s) + 1]) + " at t = " + std::to_string(time_) + " s");
      }
    }
  }
  return any;
}

void VesselEngine::probe(const ToolInput& tool) {
  VesselDynamics& d = *dynamics_;
  const V3 c = eig(tool.centre);
  for (int32_t a = 0; a < chain_->atom_count(); ++a) {
    if (d.atom_fixed(a)) continue;
    const size_t i = static_cast<size_t>(a);
    const double reach = tool.radius_mm + chain_->radius[i];
    const V3 rel = at(d.x, i) - c;
    const double dist = rel.norm();
    if (dist >= reach) continue;
    const V3 n = dist > 1e-12 ? V3(rel / dist) : V3::UnitZ();
    const V3 p = c + reach * n;
    V3 vel = at(d.v, i);
    const double inward = vel.dot(n);
    if (inward < 0) vel -= inward * n;
    for (size_t k = 0; k < 3; ++k) {
      d.x[3 * i + k] = p[static_cast<Eigen::Index>(k)];
      d.v[3 * i + k] = vel[static_cast<Eigen::Index>(k)];
    }
  }
}

StabilityReport VesselEngine::step(const std::vector<ToolInput>& tools, int steps) {
  for (int n = 0; n < steps; ++n) {
    apply_tools(tools);
    newton_ += dynamics_->step();
    for (const ToolInput& t : tools)
      if (t.acts == ToolPrimitive::push_sphere && t.active) probe(t);
    time_ += dt();
    ++steps_;
  }
  return {};
}

void VesselEngine::equilibrium(const std::vector<ToolInput>&, double) {
  throw RuntimeError(options_.where + ": the vessel model steps in time (no quasi-static solve)");
}

void VesselEngine::surface_vertices(std::vector<float>& xyz) {
  skin_->vertices(dynamics_->x, options_.skinning == VesselSkinning::rmf ? &dynamics_->q : nullptr, xyz);
}

EngineMetrics VesselEngine::metrics() const {
  EngineMetrics m;
  const VesselDynamics& d = *dynamics_;
  m.kinetic_energy = d.kinetic_energy();
  m.elastic_energy = d.elastic_energy();
  for (size_t a = 0; a < static_cast<size_t>(chain_->atom_count()); ++a) {
    m.max_displacement = std::max(m.max_displacement, (at(d.x, a) - at(chain_->rest, a)).norm());
  }
  m.springs_cut = segments_cut_;
  m.triangles_removed = segments_cut_ * 2 * skin_->spokes();
  double length = 0, strain = 0;
  for (size_t s = 0; s < alive_.size(); ++s) {
    if (!alive_[s]) continue;
    const double l = (at(d.x, static_cast<size_t>(chain_->segment_atoms[2 * s + 1])) - at(d.x, static_cast<size_t>(chain_->segment_atoms[2 * s]))).norm();
    length += l;
    strain = std::max(strain, std::abs(l / chain_->segment_length[s] - 1));
  }
  m.extra = {length, strain, static_cast<double>(newton_)};
  return m;
}

bool VesselEngine::engaged(size_t tool) const { return tool < holds_.size() && !holds_[tool].atoms.empty(); }

StabilityReport VesselEngine::check_stability() {
  StabilityReport r;
  r.time = time_;
  const VesselDynamics& d = *dynamics_;
  for (int32_t a = 0; a < chain_->atom_count(); ++a) {
    const V3 p = at(d.x, static_cast<size_t>(a));
    if (!p.allFinite() || p.norm() > 1e4) {
      r.stable = false;
      r.particle = a;
      const Vec3 rest{chain_->rest[3 * static_cast<size_t>(a)], chain_->rest[3 * static_cast<size_t>(a) + 1], chain_->rest[3 * static_cast<size_t>(a) + 2]};
      r.message = "vessel: atom " + std::to_string(a) + " (rest " + vessel_lps_text(rest, origin_) + ") is " +
                  (p.allFinite() ? "more than 10 m away" : "not finite") + " at t = " + std::to_string(time_) + " s; try dt_s " +
                  std::to_string(0.5 * dt());
      return r;
    }
  }
  const double energy = d.kinetic_energy();
  if (energy > 1e3 * (last_energy_ + d.elastic_energy()) + 1e6) {
    r.stable = false;
    r.message = "vessel: kinetic energy " + std::to_string(energy) + " nJ grew more than 1,000-fold since the last check at t = " +
                std::to_string(time_) + " s; try dt_s " + std::to_string(0.5 * dt());
    return r;
  }
  last_energy_ = energy;
  return r;
}

void VesselEngine::save_checkpoint() {
  const VesselDynamics& d = *dynamics_;
  checkpoint_ = {d.x, d.v, d.w, d.q, alive_, time_, steps_, segments_cut_};
}

void VesselEngine::restart_halved() {
  VesselDynamics& d = *dynamics_;
  d.x = checkpoint_.x;
  d.v = checkpoint_.v;
  d.w = checkpoint_.w;
  d.q = checkpoint_.q;
  time_ = checkpoint_.time;
  steps_ = checkpoint_.steps;
  // Cuts since the checkpoint stay: a blade's sweep is not replayed by the timeline's rewind.
  d.set_dt(0.5 * d.options().dt);
  last_energy_ = 0;
}

}  // namespace ctsurg::sim
