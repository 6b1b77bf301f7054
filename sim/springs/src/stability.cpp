#include "ctsurg/sim/springs/stability.h"

#include "ctsurg/core/error.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace ctsurg::sim {
namespace {

void check_safety(double safety_factor) {
  if (!(safety_factor > 0 && safety_factor <= 1))
    throw InputError("stability", "safety_factor", "must be in (0, 1], got " + std::to_string(safety_factor));
}

CriticalStep finish(const std::vector<double>& stiffness_sum, const std::vector<Real>& mass, double safety_factor) {
  CriticalStep c;
  c.safety_factor = safety_factor;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < mass.size(); ++i) {
    if (!(stiffness_sum[i] > 0)) continue;
    const double t = 2.0 * std::sqrt(mass[i] / stiffness_sum[i]);
    if (t < best) best = t, c.particle = static_cast<int32_t>(i), c.mass = mass[i], c.stiffness_sum = stiffness_sum[i];
  }
  if (c.particle < 0) throw InputError("stability", "springs", "no particle has a spring with stiffness > 0");
  c.critical = best;
  c.dt = safety_factor * best;
  return c;
}

double spring_term(const ParticleState& s, int32_t a, int32_t b, double k, double rest) {
  const double dx = double(s.x[b]) - s.x[a], dy = double(s.y[b]) - s.y[a], dz = double(s.z[b]) - s.z[a];
  const double stretch = std::sqrt(dx * dx + dy * dy + dz * dz) - rest;
  return 0.5 * k * stretch * stretch;
}

}  // namespace

CriticalStep critical_time_step(const SpringGridModel& model, double safety_factor) {
  check_safety(safety_factor);
  std::vector<double> k(model.mass.size(), 0.0);
  for (std::size_t i = 0; i < k.size(); ++i)
    for (int d = 0; d < kGridDirections; ++d)
      if (model.spring_mask[i] >> d & 1u) k[i] += model.stiffness[d];
  return finish(k, model.mass, safety_factor);
}

CriticalStep critical_time_step(const ExplicitSpringModel& model, double safety_factor) {
  check_safety(safety_factor);
  std::vector<double> k(model.mass.size(), 0.0);
  for (int32_t s = 0; s < model.spring_count(); ++s)
    if (model.alive[s]) k[model.spring_ends[2 * s]] += model.stiffness[s], k[model.spring_ends[2 * s + 1]] += model.stiffness[s];
  return finish(k, model.mass, safety_factor);
}

double kinetic_energy(const ParticleState& s, double dt) {
  double e = 0;
  for (int32_t i = 0; i < s.count(); ++i) {
    const double vx = double(s.x[i]) - s.px[i], vy = double(s.y[i]) - s.py[i], vz = double(s.z[i]) - s.pz[i];
    e += 0.5 * s.mass[i] * (vx * vx + vy * vy + vz * vz);
  }
  return e / (dt * dt);
}

double spring_energy(const SpringGridModel& model, const ParticleState& state) {
  double e = 0;
  const int64_t n = model.particle_count();
  for (int64_t a = 0; a < n; ++a)
    for (int d = 0; d < kGridDirections; ++d) {
      if ((model.spring_mask[a] >> d & 1u) == 0) continue;
      const int32_t b = model.neighbours[static_cast<std::size_t>(d * n + a)];
      if (b > a) e += spring_term(state, static_cast<int32_t>(a), b, model.stiffness[d], model.rest_length[d]);
    }
  return e;
}

double spring_energy(const ExplicitSpringModel& model, const ParticleState& state) {
  double e = 0;
  for (int32_t s = 0; s < model.spring_count(); ++s)
    if (model.alive[s])
      e += spring_term(state, model.spring_ends[2 * s], model.spring_ends[2 * s + 1], model.stiffness[s], model.rest_length[s]);
  return e;
}

std::array<double, 3> momentum(const ParticleState& s, double dt) {
  std::array<double, 3> p{0, 0, 0};
  for (int32_t i = 0; i < s.count(); ++i) {
    p[0] += s.mass[i] * (double(s.x[i]) - s.px[i]);
    p[1] += s.mass[i] * (double(s.y[i]) - s.py[i]);
    p[2] += s.mass[i] * (double(s.z[i]) - s.pz[i]);
  }
  for (double& v : p) v /= dt;
  return p;
}

StabilityGuard::StabilityGuard(std::vector<Real> rest_positions, double shortest_rest_length, double dt,
                               const StabilityGuardOptions& options)
    : rest_(std::move(rest_positions)), dt_(dt), options_(options) {
  if (!(dt > 0)) throw InputError("stability", "dt", "must be > 0");
  if (!(options.energy_growth > 1)) throw InputError("stability", "energy_growth", "must be > 1");
  max_step_ = options.max_step_mm > 0 ? options.max_step_mm : 0.5 * shortest_rest_length;
  if (!(max_step_ > 0)) throw InputError("stability", "max_step_mm", "must be > 0 (or a model with rest lengths > 0)");
}

StabilityReport StabilityGuard::check(const ParticleState& s, double time, bool external_work) {
  StabilityReport r;
  r.time = time;
  const int32_t n = s.count();
  const double limit = max_step_ + options_.gravity * std::max(time, 0.0) * dt_;
  const double limit2 = limit * limit;
  int32_t first = n;
  const int threads = std::clamp(n / 8192, 1, omp_get_max_threads());  // small models: one thread
#pragma omp parallel for schedule(static) num_threads(threads) reduction(min : first)
  for (int32_t i = 0; i < n; ++i) {
    const double dx = double(s.x[i]) - s.px[i], dy = double(s.y[i]) - s.py[i], dz = double(s.z[i]) - s.pz[i];
    const double d2 = dx * dx + dy * dy + dz * dz;
    if (!std::isfinite(d2) || d2 > limit2) first = std::min(first, i);  // NaN/inf positions give a non-finite d2
  }
  const double energy = kinetic_energy(s, dt_);
  std::ostringstream cause;
  if (first < n) {
    const double dx = double(s.x[first]) - s.px[first], dy = double(s.y[first]) - s.py[first], dz = double(s.z[first]) - s.pz[first];
    const double moved = std::sqrt(dx * dx + dy * dy + dz * dz);
    if (std::isfinite(moved))
      cause << "moved " << moved << " mm in one step (limit " << limit << " mm)";
    else
      cause << "has a non-finite position";
  } else if (!external_work && last_energy_ >= 0 && energy > options_.energy_growth * std::max(last_energy_, options_.energy_floor)) {
    cause << "kinetic energy grew from " << last_energy_ << " nJ to " << energy << " nJ since the last check";
    // Name the fastest particle.
    double best = -1;
    for (int32_t i = 0; i < n; ++i) {
      const double dx = double(s.x[i]) - s.px[i], dy = double(s.y[i]) - s.py[i], dz = double(s.z[i]) - s.pz[i];
      const double d2 = dx * dx + dy * dy + dz * dz;
      if (d2 > best) best = d2, first = i;
    }
  }
  last_energy_ = energy;
  if (cause.str().empty()) return r;
  r.stable = false;
  r.particle = first < n ? first : -1;
  std::ostringstream m;
  m << "unstable at t = " << time << " s: ";
  if (r.particle >= 0 && 3 * static_cast<std::size_t>(r.particle) + 2 < rest_.size())
    m << "particle " << r.particle << " (rest position LPS " << rest_[3 * r.particle] << ", " << rest_[3 * r.particle + 1]
      << ", " << rest_[3 * r.particle + 2] << " mm) ";
  m << cause.str() << "; try a smaller time step, e.g. dt <= " << dt_ / 2 << " s (now " << dt_ << " s)";
  r.message = m.str();
  return r;
}

void StabilityGuard::enforce(const ParticleState& state, double time) {
  const StabilityReport r = check(state, time);
  if (!r.stable) throw RuntimeError(r.message);
}

StabilityGuard make_stability_guard(const SpringGridModel& model, double dt, const StabilityGuardOptions& options) {
  return StabilityGuard(model.rest_positions, *std::min_element(model.rest_length.begin(), model.rest_length.end()), dt,
                        options);
}

StabilityGuard make_stability_guard(const ExplicitSpringModel& model, double dt, const StabilityGuardOptions& options) {
  double shortest = std::numeric_limits<double>::infinity();
  for (int32_t s = 0; s < model.spring_count(); ++s)
    if (model.rest_length[s] > 0) shortest = std::min<double>(shortest, model.rest_length[s]);
  if (!std::isfinite(shortest)) shortest = 0;
  return StabilityGuard(model.rest_positions, shortest, dt, options);
}

}  // namespace ctsurg::sim
