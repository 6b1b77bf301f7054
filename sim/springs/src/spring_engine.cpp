#include "ctsurg/sim/springs/spring_engine.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/springs/particle_removal.h"
#include "spring_stepper.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <type_traits>
#include <utility>

namespace ctsurg::sim {
namespace {

std::vector<Real> rest_of(const SpringModel& model) {
  return std::visit([](const auto& m) { return m.rest_positions; }, model);
}

// The springs present at the start (the grid counts each spring once; explicit: the alive ones).
int64_t present_springs(const SpringModel& model) {
  return std::visit([](const auto& m) -> int64_t {
    if constexpr (std::is_same_v<std::decay_t<decltype(m)>, SpringGridModel>) {
      return m.spring_count();
    } else {
      return m.alive_spring_count();
    }
  }, model);
}

double shortest_spring(const SpringModel& model) {
  return std::visit([](const auto& m) -> double {
    if constexpr (std::is_same_v<std::decay_t<decltype(m)>, SpringGridModel>) {
      return *std::min_element(m.rest_length.begin(), m.rest_length.end());
    } else {
      return m.rest_length.empty() ? 1.0 : static_cast<double>(*std::min_element(m.rest_length.begin(), m.rest_length.end()));
    }
  }, model);
}

double stiffest_spring(const SpringModel& model) {
  return std::visit([](const auto& m) -> double {
    if (m.stiffness.empty()) return 0.0;
    return static_cast<double>(*std::max_element(m.stiffness.begin(), m.stiffness.end()));
  }, model);
}

StepParameters step_parameters(double dt, const EngineOptions& o) {
  StepParameters p;
  p.dt = dt;
  p.damping = std::min(0.99, o.mass_damping * dt);
  p.gravity = o.gravity;
  p.threads = o.threads;
  return p;
}

// The state's positions as #P x 3 rows.
template <typename T>
void interleave(const ParticleState& s, std::vector<T>& xyz) {
  const size_t n = static_cast<size_t>(s.count());
  xyz.resize(3 * n);
  for (size_t i = 0; i < n; ++i) {
    xyz[3 * i] = s.x[i];
    xyz[3 * i + 1] = s.y[i];
    xyz[3 * i + 2] = s.z[i];
  }
}

std::string lps_text(const Vec3& local, const Vec3& origin) {
  return "(" + std::to_string(local[0] + origin[0]) + ", " + std::to_string(local[1] + origin[1]) + ", " +
         std::to_string(local[2] + origin[2]) + ") LPS mm";
}

}  // namespace

SpringEngine::SpringEngine(SpringModel model, ParticleState state, EmbeddedSurface surface, const Vec3& origin,
                           const EngineOptions& options, Backend backend)
    : model_(std::move(model)),
      state_(std::move(state)),
      surface_(std::move(surface)),
      origin_(origin),
      options_(options),
      rest_real_(rest_of(model_)),
      rest_(rest_real_.begin(), rest_real_.end()),
      critical_(std::visit([&](const auto& m) { return critical_time_step(m, options_.safety_factor); }, model_)),
      // A blade cuts once its centre has moved a quarter of the shortest spring (or reaches a keyframe
      // or its end): a spring cannot slip between two sweeps, and sweeping every step would cost a pass
      // over the model per step.
      blade_sweep_mm_(0.25 * shortest_spring(model_)),
      shortest_spring_mm_(shortest_spring(model_)),
      // A stitch as stiff as the stiffest tissue spring: it closes a wound against the tissue without
      // dominating a particle's spring sum (a grid particle has 18), so the auto step stays stable.
      stitch_unit_stiffness_(stiffest_spring(model_)),
      params_(step_parameters(options_.dt > 0 ? options_.dt : critical_.dt, options_)),
      guard_(make_guard()) {
  if (static_cast<size_t>(state_.count()) * 3 != rest_real_.size()) {
    throw InputError(options_.where, "state", "has " + std::to_string(state_.count()) + " particles, the model " +
                                                  std::to_string(rest_real_.size() / 3));
  }
  counts_.nodes = state_.count();
  counts_.fixed = std::count(state_.inv_mass.begin(), state_.inv_mass.end(), Real(0));
  counts_.springs = present_springs(model_);
  counts_.critical_dt_s = critical_.critical;
  if (backend == Backend::cuda) {
    stepper_ = std::make_unique<DeviceSpringStepper>(model_, state_);
    note("backend cuda: " + cuda_device_info(0).name);
  } else {
    stepper_ = std::make_unique<HostSpringStepper>(model_, state_, options_.threads);
  }
}

SpringEngine::~SpringEngine() = default;

StabilityGuard SpringEngine::make_guard() const {
  StabilityGuardOptions o;
  o.gravity = std::sqrt(options_.gravity[0] * options_.gravity[0] + options_.gravity[1] * options_.gravity[1] +
                        options_.gravity[2] * options_.gravity[2]);
  return std::visit([&](const auto& m) { return make_stability_guard(m, params_.dt, o); }, model_);
}

void SpringEngine::note(const std::string& text) const {
  if (options_.note) options_.note(text);
}

void SpringEngine::hold_components(std::vector<int32_t> components) {
  for (const int32_t c : components) {
    if (c < 0 || c >= 3 * state_.count()) throw InputError(options_.where, "fixed", "component " + std::to_string(c) + " out of range");
  }
  if (!components.empty() && stepper_->on_device()) {
    throw InputError(options_.where, "fixed", "fixing some axes only runs on the cpu backend for spring models; set backend: cpu");
  }
  held_components_ = std::move(components);
  counts_.fixed = std::count(state_.inv_mass.begin(), state_.inv_mass.end(), Real(0));
  std::vector<uint8_t> axes(static_cast<size_t>(state_.count()), 0);
  for (const int32_t c : held_components_) axes[static_cast<size_t>(c / 3)] |= static_cast<uint8_t>(1u << (c % 3));
  counts_.partly_fixed = 0;
  for (int32_t i = 0; i < state_.count(); ++i) {
    if (!axes[static_cast<size_t>(i)] || state_.inv_mass[static_cast<size_t>(i)] == Real(0)) continue;
    if (axes[static_cast<size_t>(i)] == 7) {
      ++counts_.fixed;
    } else {
      ++counts_.partly_fixed;
    }
  }
}

StabilityReport SpringEngine::step(const std::vector<ToolInput>& tools, int steps) {
  for (int k = 0; k < steps; ++k) {
    release_ended_grabs(tools);
    stepper_->step(params_);
    for (const int32_t c : held_components_) {
      const size_t i = static_cast<size_t>(c / 3);
      std::vector<Real>& x = c % 3 == 0 ? state_.x : c % 3 == 1 ? state_.y : state_.z;
      std::vector<Real>& px = c % 3 == 0 ? state_.px : c % 3 == 1 ? state_.py : state_.pz;
      x[i] = px[i] = rest_real_[static_cast<size_t>(c)];
    }
    ++steps_;
    time_ += params_.dt;
    apply_tools(tools);
  }
  return {};
}

void SpringEngine::equilibrium(const std::vector<ToolInput>&, double) {
  throw RuntimeError(options_.where + ": a spring model has no quasi-static solve (it steps in time)");
}

// A grab whose tool is no longer active after this step lets go before the step: its particles move
// freely in it. On the CPU placing happens only in apply_tools, after the step, so letting go there
// gave the same; the device places held grabs inside each step (DeviceSimulation::step), so it must
// know before stepping (found on the first GPU run: the device kept the particles one step longer).
void SpringEngine::release_ended_grabs(const std::vector<ToolInput>& tools) {
  for (size_t i = 0; i < tools.size() && i < holds_.size(); ++i) {
    Hold& h = holds_[i];
    if (tools[i].acts == ToolPrimitive::hold && h.grab && !tools[i].active) {
      h.grab.reset();
      stepper_->release_grab(h.handle);
      h.released = true;
      tool_work_ = true;  // the release turns the stretch into motion
    }
  }
}

void SpringEngine::apply_tools(const std::vector<ToolInput>& tools) {
  if (holds_.size() < tools.size()) holds_.resize(tools.size());
  for (size_t i = 0; i < tools.size(); ++i) {
    const ToolInput& tool = tools[i];
    Hold& h = holds_[i];
    switch (tool.acts) {
      case ToolPrimitive::hold:
        if (!h.grab && !h.released && tool.active) {
          h.grab = stepper_->capture({tool.centre, tool.radius_mm}, true, &h.handle);
          if (h.grab->particles.empty()) {
            throw InputError(options_.where, tool.label,
                             "grabs no free particle at t = " + std::to_string(time_) + " s (sphere of radius " +
                                 std::to_string(tool.radius_mm) + " mm at " + lps_text(tool.centre, origin_) +
                                 "; fixed particles are not grabbed); move it onto free tissue or set "
                                 "snap_to_tissue: true");
          }
          note(tool.label + ": grabbed " + std::to_string(h.grab->particles.size()) + " particles at t = " +
               std::to_string(time_) + " s");
        }
        if (h.grab) {
          stepper_->apply_grab(*h.grab, h.handle, tool.centre);
          tool_work_ = true;
        }
        break;
      case ToolPrimitive::load: {
        // An external force F shared by n free particles adds (F / n) / m dt^2 to each one's Verlet
        // update: applied after the step, as the papers apply the tools, it is the same update as a
        // force inside the step (x_next = ... + (f + F / n) / m dt^2).
        if (stepper_->on_device()) {
          throw InputError(options_.where, tool.label, "force tools run on the cpu backend only; set backend: cpu");
        }
        if (h.loaded.empty() && !h.released && tool.active) {
          const Grab inside = stepper_->capture({tool.centre, tool.radius_mm}, false, nullptr);
          for (const int32_t p : inside.particles) {
            if (state_.inv_mass[static_cast<size_t>(p)] > 0) h.loaded.push_back(p);
          }
          if (h.loaded.empty()) {
            throw InputError(options_.where, tool.label, "the force's sphere holds no free particle at t = " +
                                                             std::to_string(time_) +
                                                             " s; move it onto the tissue or set snap_to_tissue: true");
          }
          note(tool.label + ": force shared by " + std::to_string(h.loaded.size()) + " particles");
        }
        if (!h.loaded.empty() && !tool.active) {
          h.loaded.clear();
          h.released = true;
          tool_work_ = true;
        }
        const double n = static_cast<double>(h.loaded.size());
        const double dt = params_.dt;
        for (const int32_t p : h.loaded) {
          const size_t k = static_cast<size_t>(p);
          const double a = 1e6 / n * state_.inv_mass[k] * dt * dt;  // N -> uN = g mm/s^2
          state_.x[k] += static_cast<Real>(tool.force_n[0] * a);
          state_.y[k] += static_cast<Real>(tool.force_n[1] * a);
          state_.z[k] += static_cast<Real>(tool.force_n[2] * a);
        }
        tool_work_ |= !h.loaded.empty();
        break;
      }
      case ToolPrimitive::push_sphere:
        if (tool.active) tool_work_ |= stepper_->probe({tool.centre, tool.radius_mm}) > 0;
        break;
      case ToolPrimitive::push_shape:
        if (tool.active) {
          if (!tool.instrument) throw InputError(options_.where, tool.label, "the instrument has no shape");
          tool_work_ |= stepper_->push_out(instrument_view(*tool.instrument, tool.orientation, tool.centre)) > 0;
        }
        break;
      case ToolPrimitive::separate:
        for (const auto& [from, to] : tool.sweeps) {
          sweep_blade(tool, from, to);
          tool_work_ = true;
        }
        break;
      case ToolPrimitive::stitch:
        if (h.stitches.empty() && !h.released && tool.active) place_stitches(tool, h);
        if (!h.stitches.empty()) {
          apply_stitches(state_, h.stitches, h.schedule, time_, params_.dt);
          // While the knots tighten the stitches do work on the tissue; afterwards they are plain springs.
          tool_work_ |= time_ < h.schedule.end_s;
        }
        break;
      case ToolPrimitive::remove:
        if (tool.active) {
          remove_tissue(tool, h);
        } else {
          h.removal_budget_mm3 = 0;  // the tip is off: nothing carries over to its next touch
        }
        break;
    }
  }
}

double SpringEngine::spring_sum(int32_t particle) const {
  const size_t i = static_cast<size_t>(particle);
  return std::visit([&](const auto& m) -> double {
    double k = 0;
    if constexpr (std::is_same_v<std::decay_t<decltype(m)>, SpringGridModel>) {
      for (int d = 0; d < kGridDirections; ++d) {
        if (m.spring_mask[i] & (1u << d)) k += m.stiffness[static_cast<size_t>(d)];
      }
    } else {
      for (int32_t e = m.row_offsets[i]; e < m.row_offsets[i + 1]; ++e) {
        const size_t sp = static_cast<size_t>(m.row_spring[static_cast<size_t>(e)]);
        if (m.alive[sp]) k += m.stiffness[sp];
      }
    }
    return k;
  }, model_);
}

// Places a suture's stitches on the particles nearest to their points at rest, after checking that the
// explicit step stays stable with them (suture.h).
void SpringEngine::place_stitches(const ToolInput& suture, Hold& h) {
  if (stepper_->on_device()) {
    throw InputError(options_.where, suture.label, "sutures run on the cpu backend only; set backend: cpu");
  }
  stepper_->to_host();
  std::vector<Stitch> stitches = attach_stitches(suture.stitches, suture.stitch_fields, rest_real_, state_,
                                                 kStitchSnapCells * shortest_spring_mm_, options_.where);
  const double k = suture.stitch_stiffness_ratio * stitch_unit_stiffness_;
  std::vector<double> added(static_cast<size_t>(state_.count()), 0.0);
  for (const Stitch& st : stitches) {
    added[static_cast<size_t>(st.a)] += k;
    added[static_cast<size_t>(st.b)] += k;
  }
  for (const Stitch& st : stitches) {
    for (const int32_t p : {st.a, st.b}) {
      const size_t i = static_cast<size_t>(p);
      const double m = state_.inv_mass[i] > 0 ? 1.0 / state_.inv_mass[i] : 0.0;
      const double limit = stitch_step_limit(m, spring_sum(p), added[i]);
      if (params_.dt > limit) {
        // The largest ratio that keeps this particle stable with its n stitch ends: K + n r u = 2 m / dt^2.
        const double ends = std::round(added[i] / k), spring = spring_sum(p);
        const double ratio = std::max(0.0, 2 * m / (params_.dt * params_.dt) - spring) / (ends * stitch_unit_stiffness_);
        char text[400];
        std::snprintf(text, sizeof text,
                      "%.4g (stitches of %.4g g/s^2) makes particle %d (mass %.4g g, springs %.4g g/s^2, %.0f stitch ends) "
                      "unstable: it needs a step <= %.4g s, the run's is %.4g s; lower stiffness_ratio to <= %.3g or "
                      "set time.dt_s <= %.4g",
                      suture.stitch_stiffness_ratio, k, p, m, spring, ends, limit, params_.dt, ratio, limit);
        throw InputError(options_.where, suture.label + ".stiffness_ratio", text);
      }
    }
  }
  h.stitches = std::move(stitches);
  h.schedule = {suture.start_s, suture.end_s, suture.stitch_target_mm, k};
  note(suture.label + ": " + std::to_string(h.stitches.size()) + " stitches placed at t = " + std::to_string(time_) +
       " s, " + std::to_string(k) + " g/s^2 each");
}

std::vector<std::array<Vec3, 2>> SpringEngine::stitches(size_t tool) const {
  std::vector<std::array<Vec3, 2>> out;
  if (tool >= holds_.size()) return out;
  for (const Stitch& st : holds_[tool].stitches) {
    const size_t a = static_cast<size_t>(st.a), b = static_cast<size_t>(st.b);
    out.push_back({Vec3{state_.x[a] + st.offset_a[0], state_.y[a] + st.offset_a[1], state_.z[a] + st.offset_a[2]},
                   Vec3{state_.x[b] + st.offset_b[0], state_.y[b] + st.offset_b[1], state_.z[b] + st.offset_b[2]}});
  }
  return out;
}

// Removes the tissue inside a remove tool's sphere (a cautery) at its rate: the budget grows by rate x dt
// each step while the tip is on and is spent on the particles nearest its centre (particle_removal.h);
// with nothing left in reach it does not build up. The surface over the removed particles is opened
// and, with close_cuts, closed over the crater.
void SpringEngine::remove_tissue(const ToolInput& tool, Hold& h) {
  if (stepper_->on_device()) {
    throw InputError(options_.where, tool.label, std::string(tool.name) + " runs on the cpu backend only; set backend: cpu");
  }
  if (!(options_.density > 0)) {
    throw InputError(options_.where, tool.label, "the engine was built without the tissue's density (EngineOptions::density)");
  }
  h.removal_budget_mm3 += tool.removal_rate_mm3_s * params_.dt;
  if (removed_.empty()) removed_.assign(static_cast<size_t>(state_.count()), 0);
  const Sphere tip{tool.centre, tool.radius_mm};
  const RemovalResult r = std::visit(
      [&](auto& m) { return remove_particles_in_sphere(m, state_, removed_, tip, options_.density, &h.removal_budget_mm3); }, model_);
  if (r.exhausted) h.removal_budget_mm3 = 0;
  if (r.particles.empty()) return;
  removed_volume_ += r.volume_mm3;
  removed_particles_ += static_cast<int64_t>(r.particles.size());
  springs_cut_ += r.springs;
  tool_work_ = true;
  if (!surface_.empty()) {
    const int64_t opened = surface_.remove_tied_to(removed_);
    triangles_removed_ += opened;
    if (opened > 0) {
      surface_.move(state_, rest_real_, vertices_, options_.threads);
      surface_.close_cut_holes(vertices_);
    }
  }
}

// Cuts the springs and the surface crossing the quad the blade's edge swept from centre `from` to `to`.
void SpringEngine::sweep_blade(const ToolInput& blade, const Vec3& from, const Vec3& to) {
  stepper_->to_host();
  if (!surface_.empty()) surface_.move(state_, rest_real_, vertices_, options_.threads);
  int64_t removed = 0;
  for (const Triangle& tri : swept_blade(from, to, blade.blade_edge_mm)) {
    if (!surface_.empty()) removed += surface_.cut(tri, vertices_, state_);
    springs_cut_ += stepper_->cut(tri);
  }
  triangles_removed_ += removed;
  // The holes are closed over the vertices where they are now, before the lips separate.
  if (removed > 0) surface_.close_cut_holes(vertices_);
}

void SpringEngine::sync() { stepper_->to_host(); }

void SpringEngine::positions(std::vector<double>& xyz) const { interleave(state_, xyz); }

void SpringEngine::surface_vertices(std::vector<float>& xyz) {
  if (surface_.empty()) {
    interleave(state_, xyz);  // no surface: the particles
  } else {
    surface_.move(state_, rest_real_, xyz, options_.threads);
  }
}

EngineMetrics SpringEngine::metrics() const {
  EngineMetrics m;
  m.kinetic_energy = kinetic_energy(state_, params_.dt);
  m.elastic_energy = std::visit([&](const auto& model) { return spring_energy(model, state_); }, model_);
  double max_disp = 0;
  for (int32_t i = 0; i < state_.count(); ++i) {
    const size_t k = static_cast<size_t>(i);
    const double d = std::pow(state_.x[k] - rest_real_[3 * k], 2) + std::pow(state_.y[k] - rest_real_[3 * k + 1], 2) +
                     std::pow(state_.z[k] - rest_real_[3 * k + 2], 2);
    max_disp = std::max(max_disp, d);
  }
  m.max_displacement = std::sqrt(max_disp);
  m.springs_cut = springs_cut_;
  m.triangles_removed = triangles_removed_;
  m.removed_volume = removed_volume_;
  return m;
}

bool SpringEngine::engaged(size_t tool) const {
  return tool < holds_.size() && (holds_[tool].grab.has_value() || !holds_[tool].loaded.empty());
}

StabilityReport SpringEngine::check_stability() {
  stepper_->to_host();
  const StabilityReport r = guard_.check(state_, time_, tool_work_);
  tool_work_ = false;
  return r;
}

bool SpringEngine::can_restart() const { return !stepper_->on_device(); }

void SpringEngine::save_checkpoint() {
  if (!can_restart()) throw RuntimeError(options_.where + ": a spring model on a CUDA device does not restart");
  checkpoint_ = Checkpoint{state_, model_, holds_, surface_, removed_, time_, steps_, springs_cut_, triangles_removed_,
                           removed_particles_, removed_volume_};
}

void SpringEngine::restart_halved() {
  if (!checkpoint_) throw RuntimeError(options_.where + ": no checkpoint to restart from");
  const Checkpoint& c = *checkpoint_;
  state_ = c.state;
  model_ = c.model;
  holds_ = c.holds;
  surface_ = c.surface;
  time_ = c.time;
  steps_ = c.steps;
  springs_cut_ = c.springs_cut;
  triangles_removed_ = c.triangles_removed;
  removed_ = c.removed;
  removed_particles_ = c.removed_particles;
  removed_volume_ = c.removed_volume;
  // Verlet's previous positions are rescaled so that the velocities stay the same:
  // x_prev = x - (x - x_prev) / 2.
  for (int32_t i = 0; i < state_.count(); ++i) {
    const size_t k = static_cast<size_t>(i);
    state_.px[k] = state_.x[k] - (state_.x[k] - state_.px[k]) / 2;
    state_.py[k] = state_.y[k] - (state_.y[k] - state_.py[k]) / 2;
    state_.pz[k] = state_.z[k] - (state_.z[k] - state_.pz[k]) / 2;
  }
  params_ = step_parameters(params_.dt / 2, options_);
  guard_ = make_guard();
  tool_work_ = true;  // the restart changes the energy the guard last saw
}

}  // namespace ctsurg::sim
