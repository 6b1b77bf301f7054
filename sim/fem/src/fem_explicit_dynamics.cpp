#include "ctsurg/sim/fem/fem_explicit_dynamics.h"

#include "fem_cpu_kernels.h"
#include "fem_element_view.h"
#include "fem_device_dynamics.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/fem/fem_forces.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

namespace ctsurg::sim {
namespace {

constexpr const char* kExplicitWhere = "fem dynamics";

std::string rest_text(const double* p) {
  std::ostringstream s;
  s << "(" << p[0] << ", " << p[1] << ", " << p[2] << ") mm";
  return s.str();
}

// The rest centroid of element e, LPS mm.
std::array<double, 3> centroid(const FemModel& m, int32_t e) {
  std::array<double, 3> c{0, 0, 0};
  for (int a = 0; a < 4; ++a)
    for (int k = 0; k < 3; ++k) c[k] += m.nodes[3 * m.tets[4 * e + a] + k] / 4;
  return fem_lps_point(m, c.data());
}

// The guard's messages (one text for both backends). time, step: before the failing step.
RuntimeError inverted_error(const FemModel& model, int32_t element, double time, int64_t step, double dt) {
  const auto ctr = centroid(model, element);
  std::ostringstream m;
  m << "fem dynamics: element " << element << " (rest centroid " << rest_text(ctr.data()) << ") inverted (det F <= 0) at t = "
    << time << " s (step " << step << ", dt = " << dt << " s); the state before this step is kept. Likely causes: a "
    << "grab or probe moving faster than the tissue can follow, or a step too large (suggested: dt <= "
    << 0.5 * dt << " s, or smaller tool increments)";
  return RuntimeError(m.str());
}

RuntimeError non_finite_error(const FemModel& model, int32_t node, double time, double dt) {
  std::ostringstream m;
  m << "fem dynamics: node " << node << " (rest " << rest_text(fem_lps_point(model, &model.nodes[3 * node]).data())
    << ") got a non-finite displacement at t = " << time + dt << " s; the state before this step is kept "
    << "(suggested: dt <= " << 0.5 * dt << " s)";
  return RuntimeError(m.str());
}

// time: after the step whose check failed.
RuntimeError energy_growth_error(double before, double after, int interval, double time, double dt) {
  std::ostringstream m;
  m << "fem dynamics: kinetic energy grew from " << before << " to " << after << " nJ within " << interval
    << " steps at t = " << time << " s (dt = " << dt << " s): the integration is unstable; suggested: dt <= "
    << 0.5 * dt << " s";
  return RuntimeError(m.str());
}

// The kernels' views of the model with Real copies of B and V.
FemElementView<Real> element_view(const FemModel& model, const std::vector<Real>& dm_inverse, const std::vector<Real>& volume) {
  return fem_element_view<Real>(model, dm_inverse.data(), volume.data());
}

// fem_explicit_step_impl.h's coefficients of eq. 12 for step dt (s), mass damping (1/s), gravity (mm/s^2).
FemStepConstants step_constants(double dt, double mass_damping, const std::array<double, 3>& gravity) {
  const double c = mass_damping * dt / 2;
  return {static_cast<Real>(dt * dt / (1 + c)), static_cast<Real>(2 / (1 + c)), static_cast<Real>((1 - c) / (1 + c)),
          static_cast<Real>(gravity[0]),        static_cast<Real>(gravity[1]), static_cast<Real>(gravity[2])};
}

}  // namespace

FemCriticalStep fem_critical_time_step(const FemModel& model, double safety_factor) {
  if (!(safety_factor > 0 && safety_factor <= 1))
    throw InputError("fem critical step", "safety_factor", "must be in (0, 1], got " + std::to_string(safety_factor));
  if (model.order != 1) throw InputError("fem critical step", "order", "the explicit dynamics runs linear tets only");
  FemCriticalStep cs;
  cs.safety_factor = safety_factor;
  // The dilatational wave speed of each material (the critical step is the smallest h_e / c_e).
  std::vector<double> speed;
  for (std::size_t k = 0; k < model.materials.size(); ++k)
    speed.push_back(std::sqrt((model.lame[k].lambda + 2 * model.lame[k].mu) / model.materials[k].density));
  cs.wave_speed = speed[0];
  cs.length = HUGE_VAL;
  double shortest = HUGE_VAL;  // h_e / c_e
  static const int faces[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  for (int32_t e = 0; e < model.tet_count(); ++e) {
    double largest = 0;
    for (const auto& f : faces) {
      const double* p0 = &model.nodes[3 * model.tets[4 * e + f[0]]];
      const double* p1 = &model.nodes[3 * model.tets[4 * e + f[1]]];
      const double* p2 = &model.nodes[3 * model.tets[4 * e + f[2]]];
      const double a[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
      const double b[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
      const double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
      largest = std::max(largest, 0.5 * std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]));
    }
    const double h = 3 * model.rest_volume[e] / largest;
    if (speed.size() == 1) {
      if (h < cs.length) {
        cs.length = h;
        cs.element = e;
      }
    } else if (const double c = speed[static_cast<std::size_t>(model.material_index(e))]; h / c < shortest) {
      shortest = h / c;
      cs.length = h;
      cs.wave_speed = c;
      cs.element = e;
    }
  }
  cs.critical = cs.length / cs.wave_speed;
  cs.dt = safety_factor * cs.critical;
  return cs;
}

FemExplicitDynamics::FemExplicitDynamics(const FemModel& model, const FemDynamicsOptions& options, Backend backend)
    : model_(model), options_(options) {
  if (!backend_available(backend)) require_backend(backend, kExplicitWhere);  // cuda without a CUDA build or device: says why
  if (model.order != 1)
    throw InputError(kExplicitWhere, "order", "the explicit dynamics runs linear tets only (quadratic ones: the static or implicit solver)");
  const auto& o = options;
  if (!(o.mass_damping >= 0 && std::isfinite(o.mass_damping))) throw InputError(kExplicitWhere, "mass_damping", "must be finite and >= 0 (1/s)");
  for (double g : o.gravity)
    if (!std::isfinite(g)) throw InputError(kExplicitWhere, "gravity", "must be finite");
  if (o.energy_check_interval < 1) throw InputError(kExplicitWhere, "energy_check_interval", "must be >= 1");
  if (!(o.energy_growth > 1)) throw InputError(kExplicitWhere, "energy_growth", "must be > 1");
  if (!(o.energy_floor >= 0)) throw InputError(kExplicitWhere, "energy_floor", "must be >= 0");
  if (o.threads < 0) throw InputError(kExplicitWhere, "threads", "must be >= 0");
  const FemCriticalStep cs = fem_critical_time_step(model, o.safety_factor);
  if (o.dt == 0) {
    dt_ = cs.dt;
  } else {
    if (!(o.dt > 0 && std::isfinite(o.dt))) throw InputError(kExplicitWhere, "dt", "must be finite and > 0 s, or 0 (automatic)");
    if (o.dt > cs.critical)
      throw InputError(kExplicitWhere, "dt", "step " + std::to_string(o.dt) + " s exceeds the critical step " +
                                         std::to_string(cs.critical) + " s of element " + std::to_string(cs.element) +
                                         "; use <= " + std::to_string(cs.dt) + " s");
    dt_ = o.dt;
  }
  const std::size_t n3 = 3 * static_cast<std::size_t>(model.node_count());
  dm_inverse_.assign(model.dm_inverse.begin(), model.dm_inverse.end());
  volume_.assign(model.rest_volume.begin(), model.rest_volume.end());
  fixed_.assign(model.node_count(), 0);
  if (backend == Backend::cuda) {
    device_ = std::make_unique<FemDeviceDynamics>(
        model, dm_inverse_, volume_, step_constants(dt_, o.mass_damping, o.gravity), dt_,
        FemDeviceGuard{o.energy_check_interval, o.energy_growth, o.energy_floor}, kExplicitWhere);
  } else {
    u_.assign(n3, 0);
    u_prev_.assign(n3, 0);
    u_next_.assign(n3, 0);
    corner_forces_.assign(12 * static_cast<std::size_t>(model.tet_count()), 0);
  }
  if (o.contact.enabled) {
    if (device_) throw InputError(kExplicitWhere, "contact", "contact between bodies runs on the cpu backend only; set backend: cpu");
    FemContactOptions c = o.contact;
    if (c.threads == 0) c.threads = o.threads;
    contact_ = std::make_unique<FemContact>(model, c);
  }
  update_inverse_mass();
}

FemExplicitDynamics::~FemExplicitDynamics() = default;
FemExplicitDynamics::FemExplicitDynamics(FemExplicitDynamics&&) noexcept = default;

void FemExplicitDynamics::update_inverse_mass() {
  const int32_t n = model_.node_count();
  inv_mass_.assign(n, 0);
  for (int32_t i = 0; i < n; ++i)
    if (!fixed_[i] && model_.node_mass[i] > 0) inv_mass_[i] = static_cast<Real>(1.0 / model_.node_mass[i]);
  for (int32_t i : prescribed_nodes_) inv_mass_[i] = 0;
  if (device_) device_->set_inverse_mass(inv_mass_);
}

void FemExplicitDynamics::set_fixed_nodes(const std::vector<int32_t>& nodes) {
  for (int32_t i : nodes)
    if (i < 0 || i >= model_.node_count()) throw InputError(kExplicitWhere, "fixed_nodes", "node id " + std::to_string(i) + " out of range");
  fixed_.assign(model_.node_count(), 0);
  for (int32_t i : nodes) {
    fixed_[i] = 1;
    if (!device_)
      for (int c = 0; c < 3; ++c) u_[3 * i + c] = u_prev_[3 * i + c] = 0;
  }
  if (device_) device_->zero_nodes(nodes);
  update_inverse_mass();
}

void FemExplicitDynamics::set_prescribed(const std::vector<int32_t>& nodes, const std::vector<double>& displacements) {
  if (displacements.size() != 3 * nodes.size())
    throw InputError(kExplicitWhere, "prescribed_displacements", "expected #G x 3 = " + std::to_string(3 * nodes.size()) + " values");
  for (int32_t i : nodes)
    if (i < 0 || i >= model_.node_count()) throw InputError(kExplicitWhere, "prescribed_nodes", "node id " + std::to_string(i) + " out of range");
  for (double d : displacements)
    if (!std::isfinite(d)) throw InputError(kExplicitWhere, "prescribed_displacements", "must be finite");
  const bool same_nodes = nodes == prescribed_nodes_;
  prescribed_nodes_ = nodes;
  prescribed_.assign(displacements.begin(), displacements.end());
  if (device_) device_->set_prescribed(prescribed_nodes_, prescribed_);
  if (!same_nodes) update_inverse_mass();  // a moving grab (same nodes, new values) keeps the masses
}

void FemExplicitDynamics::clear_prescribed() {
  prescribed_nodes_.clear();
  prescribed_.clear();
  if (device_) device_->set_prescribed(prescribed_nodes_, prescribed_);
  update_inverse_mass();
}

void FemExplicitDynamics::set_external_forces(const std::vector<double>& forces) {
  if (!forces.empty() && forces.size() != 3 * static_cast<std::size_t>(model_.node_count()))
    throw InputError(kExplicitWhere, "forces", "expected #N x 3 values or none");
  for (double f : forces)
    if (!std::isfinite(f)) throw InputError(kExplicitWhere, "forces", "must be finite");
  external_.assign(forces.begin(), forces.end());
  if (device_) device_->set_external_forces(external_);
}

void FemExplicitDynamics::set_contact_sphere(const std::array<double, 3>& centre, double radius) {
  for (double c : centre)
    if (!std::isfinite(c)) throw InputError(kExplicitWhere, "sphere centre", "must be finite");
  if (!(std::isfinite(radius) && radius >= 0)) throw InputError(kExplicitWhere, "sphere radius", "must be finite and >= 0 mm");
  sphere_ = {centre[0], centre[1], centre[2], radius};
  if (device_) device_->set_contact_sphere(FemSphereView{sphere_[0], sphere_[1], sphere_[2], sphere_[3]});
}

void FemExplicitDynamics::set_contact_instruments(const std::vector<InstrumentView>& instruments) {
  if (device_ && !instruments.empty()) {
    throw InputError(kExplicitWhere, "instruments", "instrument contact runs on the cpu backend only; set backend: cpu");
  }
  for (const InstrumentView& v : instruments) check_instrument_view(v, kExplicitWhere, "instruments");
  instruments_ = instruments;
}

void FemExplicitDynamics::step(int steps) {
  if (steps < 0) throw InputError(kExplicitWhere, "steps", "must be >= 0");
  if (device_) return step_on_device(steps);
  const FemElementView<Real> el = element_view(model_, dm_inverse_, volume_);
  const FemStepConstants k = step_constants(dt_, options_.mass_damping, options_.gravity);
  for (int s = 0; s < steps; ++s) {
    const FemNodeView nv{model_.node_offsets.data(), model_.node_corners.data(), u_.data(), u_prev_.data(),
                         u_next_.data(), inv_mass_.data(), external_.empty() ? nullptr : external_.data(),
                         model_.node_count()};
    int32_t bad_node = -1;
    const int32_t inverted = cpu::fem_explicit_step(el, nv, k, corner_forces_.data(), options_.threads, &bad_node);
    if (inverted >= 0) throw inverted_error(model_, inverted, time_, steps_, dt_);
    if (bad_node >= 0) throw non_finite_error(model_, bad_node, time_, dt_);
    for (std::size_t g = 0; g < prescribed_nodes_.size(); ++g)
      for (int a = 0; a < 3; ++a) u_next_[3 * prescribed_nodes_[g] + a] = prescribed_[3 * g + a];
    contacts_ = 0;
    if (sphere_[3] > 0)
      contacts_ = cpu::fem_sphere_contact(u_next_.data(), model_.nodes.data(), inv_mass_.data(), model_.node_count(),
                                          FemSphereView{sphere_[0], sphere_[1], sphere_[2], sphere_[3]}, options_.threads);
    for (const InstrumentView& v : instruments_)
      contacts_ += cpu::fem_instrument_contact(u_next_.data(), model_.nodes.data(), inv_mass_.data(), model_.node_count(), v,
                                               options_.threads);
    if (contact_) contacts_ += contact_->resolve(model_, u_next_.data(), inv_mass_.data());
    u_prev_.swap(u_);
    u_.swap(u_next_);
    time_ += dt_;
    ++steps_;
    if (steps_ % options_.energy_check_interval == 0) {
      const double e = kinetic_energy();
      if (last_energy_ > options_.energy_floor && e > options_.energy_growth * last_energy_)
        throw energy_growth_error(last_energy_, e, options_.energy_check_interval, time_, dt_);
      last_energy_ = e;
    }
  }
}

// The device runs the steps and the guard; here the clock advances by the steps it applied (one
// addition per step, as on the CPU, so that time() has the same bits) and a stop becomes the CPU's error.
void FemExplicitDynamics::step_on_device(int steps) {
  const FemDeviceStepOutcome r = device_->step(steps, steps_);
  for (int64_t s = 0; s < r.completed; ++s) time_ += dt_;
  steps_ += r.completed;
  if (r.completed > 0) contacts_ = r.contacts;
  if (r.inverted_element >= 0) throw inverted_error(model_, r.inverted_element, time_, steps_, dt_);
  if (r.non_finite_node >= 0) throw non_finite_error(model_, r.non_finite_node, time_, dt_);
  if (r.energy_grew) throw energy_growth_error(r.energy_before, r.energy_after, options_.energy_check_interval, time_, dt_);
}

std::vector<Real> FemExplicitDynamics::raw_displacements() const { return device_ ? device_->displacements() : u_; }

std::vector<Real> FemExplicitDynamics::raw_previous_displacements() const {
  if (device_) throw InputError(kExplicitWhere, "backend", "the previous displacements are kept on the device");
  return u_prev_;
}

void FemExplicitDynamics::restore_state(const std::vector<Real>& u, const std::vector<Real>& u_prev, double time, int64_t steps) {
  if (device_) throw InputError(kExplicitWhere, "backend", "restoring a state runs on the cpu backend only");
  if (u.size() != u_.size() || u_prev.size() != u_.size()) throw InputError(kExplicitWhere, "state", "expected #N x 3 displacements, twice");
  for (size_t i = 0; i < u.size(); ++i)
    if (!std::isfinite(u[i]) || !std::isfinite(u_prev[i])) throw InputError(kExplicitWhere, "state", "a displacement is not finite");
  u_ = u;
  u_prev_ = u_prev;
  time_ = time;
  steps_ = steps;
  last_energy_ = kinetic_energy();
}

std::vector<double> FemExplicitDynamics::displacements() const {
  if (device_) {
    const std::vector<Real> u = device_->displacements();
    return {u.begin(), u.end()};
  }
  return {u_.begin(), u_.end()};
}

std::vector<double> FemExplicitDynamics::positions() const {
  std::vector<double> p = displacements();
  for (std::size_t d = 0; d < p.size(); ++d) p[d] += model_.nodes[d];
  return p;
}

double FemExplicitDynamics::kinetic_energy() const {
  if (device_) return device_->kinetic_energy();
  double e = 0;
  for (int32_t i = 0; i < model_.node_count(); ++i) {
    double v2 = 0;
    for (int c = 0; c < 3; ++c) {
      const double v = (static_cast<double>(u_[3 * i + c]) - u_prev_[3 * i + c]) / dt_;
      v2 += v * v;
    }
    e += 0.5 * model_.node_mass[i] * v2;
  }
  return e;
}

double FemExplicitDynamics::strain_energy() const { return fem_strain_energy(model_, displacements()); }

std::vector<Real> FemExplicitDynamics::internal_forces() {
  if (device_) return device_->internal_forces();
  const FemElementView<Real> el = element_view(model_, dm_inverse_, volume_);
  std::vector<Real> f(u_.size());
  cpu::fem_forces(el, model_.node_offsets.data(), model_.node_corners.data(), model_.node_count(), u_.data(),
                  corner_forces_.data(), f.data(), options_.threads);
  return f;
}

}  // namespace ctsurg::sim
