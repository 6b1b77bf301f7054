#include "ctsurg/sim/fem/fem_engine.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/base/parallel.h"
#include "ctsurg/sim/fem/fem_forces.h"
#include "ctsurg/sim/fem/kernels/fem_quadratic_element_impl.h"
#include "fem_rigid_modes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numeric>
#include <utility>

namespace ctsurg::sim {
namespace {

// Per node: 1 when a support holds it, wholly or in some component (tools do not capture it).
std::vector<uint8_t> fixed_flags(int32_t nodes, const FemBoundaryConditions& supports) {
  std::vector<uint8_t> flags(static_cast<size_t>(nodes), 0);
  for (const int32_t n : supports.fixed_nodes) {
    if (n < 0 || n >= nodes) throw InputError("fem engine", "fixed", "node " + std::to_string(n) + " out of range");
    flags[static_cast<size_t>(n)] = 1;
  }
  for (const int32_t c : supports.fixed_components) {
    if (c < 0 || c >= 3 * nodes) throw InputError("fem engine", "fixed", "component " + std::to_string(c) + " out of range");
    flags[static_cast<size_t>(c / 3)] = 1;
  }
  return flags;
}

// For each surface vertex of `coupling` (slots 0..3: the corners of a linear tet, weights: barycentric),
// the quadratic element with those corners and its 10 shape-function values there.
void quadratic_surface(const FemModel& model, const SurfaceCoupling& coupling, std::vector<int32_t>& nodes, std::vector<double>& weights) {
  std::map<std::array<int32_t, 4>, int32_t> element_of;
  for (int32_t e = 0; e < model.tet_count(); ++e) {
    std::array<int32_t, 4> key;
    for (int a = 0; a < 4; ++a) key[a] = model.tets[10 * static_cast<size_t>(e) + a];
    std::sort(key.begin(), key.end());
    element_of.emplace(key, e);
  }
  const int64_t nv = coupling.vertex_count();
  nodes.resize(10 * static_cast<size_t>(nv));
  weights.resize(10 * static_cast<size_t>(nv));
  for (int64_t v = 0; v < nv; ++v) {
    std::array<int32_t, 4> key;
    for (int a = 0; a < 4; ++a) key[a] = coupling.particles[8 * static_cast<size_t>(v) + a];
    std::sort(key.begin(), key.end());
    const auto it = element_of.find(key);
    if (it == element_of.end()) throw InputError("fem engine", "surface", "vertex " + std::to_string(v) + " is not tied to a tet of the model");
    const int32_t* t = &model.tets[10 * static_cast<size_t>(it->second)];
    double l[4] = {0, 0, 0, 0};
    for (int a = 0; a < 4; ++a)
      for (int k = 0; k < 4; ++k)
        if (coupling.particles[8 * static_cast<size_t>(v) + k] == t[a]) l[a] = coupling.weights[8 * static_cast<size_t>(v) + k];
    double N[10];
    fem_quadratic_shape(l, N);
    for (int a = 0; a < 10; ++a) {
      nodes[10 * static_cast<size_t>(v) + a] = t[a];
      weights[10 * static_cast<size_t>(v) + a] = N[a];
    }
  }
}

}  // namespace

FemEngine::FemEngine(FemModel model, FemBoundaryConditions supports, EmbeddedSurface surface, const Vec3& origin,
                     const FemEngineOptions& options, Backend backend)
    : model_(std::move(model)),
      supports_(std::move(supports)),
      surface_(std::move(surface)),
      origin_(origin),
      options_(options),
      backend_(backend),
      holds_(model_, fixed_flags(model_.node_count(), supports_), options_.where, options_.note),
      u_(model_.nodes.size(), 0.0),
      rest_real_(model_.nodes.begin(), model_.nodes.end()),
      positions_(rest_real_, std::vector<Real>(static_cast<size_t>(model_.node_count()), Real(1))) {
  counts_.nodes = model_.node_count();
  counts_.elements = model_.tet_count();
  const std::vector<uint8_t> held = fixed_flags(model_.node_count(), supports_);
  counts_.fixed = std::count(held.begin(), held.end(), uint8_t{1});
  supports_.prescribed_nodes.clear();
  supports_.prescribed_displacements.clear();
  if (model_.order == 2 && !surface_.empty()) quadratic_surface(model_, surface_.coupling(), quadratic_nodes_, quadratic_weights_);
  if (options_.solver == FemSolver::dynamic) {
    FemDynamicsOptions o;  // the explicit dynamics' own options struct: every field it needs, from ours
    o.dt = options_.dt;
    o.safety_factor = options_.safety_factor;
    o.mass_damping = options_.mass_damping;
    o.gravity = options_.gravity;
    o.threads = options_.threads;
    counts_.critical_dt_s = fem_critical_time_step(model_, options_.safety_factor).critical;
    if (!supports_.fixed_components.empty()) {
      throw InputError(options_.where, "fixed", "the explicit dynamics fixes whole nodes; fixing some axes needs the static or implicit solver");
    }
    dynamics_.emplace(model_, o, backend_);
    dynamics_->set_fixed_nodes(supports_.fixed_nodes);
    return;
  }
  if (options_.solver == FemSolver::implicit) {
    FemImplicitOptions o;
    o.dt = options_.dt > 0 ? options_.dt : 1.0 / 60;
    o.mass_damping = options_.mass_damping;
    o.stiffness_damping = options_.stiffness_damping;
    o.gravity = options_.gravity;
    o.threads = options_.threads;
    o.newton = options_.newton;
    implicit_ = std::make_unique<FemImplicitDynamics>(model_, o, backend_);
    implicit_->set_supports(supports_.fixed_nodes, supports_.fixed_components);
    return;
  }
  // Quasi-static. The linear material factorises its constant stiffness once; the nonlinear laws run
  // Newton with conjugate gradients per frame.
  if (supports_.fixed_nodes.empty() && supports_.fixed_components.empty()) {
    throw InputError(options_.where, "fixed", "a static FEM problem needs fixed nodes (the system is singular otherwise)");
  }
  bc_ = supports_;
  FemStaticOptions newton = options_.newton;
  newton.threads = options_.threads;
  newton.initial_displacements.clear();
  // The linear law's condensation (fem_linear_static_solver.h) needs supports that hold the model on
  // their own; where a grab completes them (a roller and a grab), Newton's solver holds both.
  std::vector<uint8_t> supported(3 * static_cast<size_t>(model_.node_count()), 0);
  for (const int32_t n : supports_.fixed_nodes) supported[3 * static_cast<size_t>(n)] = supported[3 * static_cast<size_t>(n) + 1] =
      supported[3 * static_cast<size_t>(n) + 2] = 1;
  for (const int32_t c : supports_.fixed_components) supported[static_cast<size_t>(c)] = 1;
  const bool supports_hold = free_rigid_modes(model_, supported, fem_bounding_diagonal(model_)).empty();
  if (model_.material.model == FemMaterialModel::linear && model_.order == 1 && newton.linear_solve != FemLinearSolve::iterative &&
      supports_hold) {
    FemLinearSolverOptions lo;
    lo.threads = options_.threads;
    linear_ = std::make_unique<FemLinearStaticSolver>(model_, bc_, lo);
    if (options_.note) {
      options_.note("FEM linear static: stiffness factorised once (" + std::to_string(linear_->stats().factor_nonzeros) +
                    " non-zeros, " + std::to_string(linear_->stats().factor_seconds) + " s); each frame a condensed solve");
    }
  } else {
    static_solver_ = std::make_unique<FemStaticSolver>(model_, newton, backend_);
  }
}

FemEngine::~FemEngine() = default;

std::vector<std::pair<std::string, std::string>> FemEngine::extra_metrics() const {
  return {{"newton_iterations", "1"}, {"cg_iterations", "1"}};
}

double FemEngine::dt() const { return dynamics_ ? dynamics_->dt() : implicit_ ? implicit_->dt() : 0.0; }
double FemEngine::time() const { return dynamics_ ? dynamics_->time() : implicit_ ? implicit_->time() : static_time_; }

void FemEngine::check_tools(const std::vector<ToolInput>& tools) const {
  for (const ToolInput& tool : tools) {
    if (tool.kind == ToolKind::cut) throw InputError(options_.where, tool.label, "the FEM models do not cut; use a spring model");
    if ((tool.kind == ToolKind::probe || tool.kind == ToolKind::instrument) && !dynamics_) {
      throw InputError(options_.where, tool.label,
                       std::string(to_string(tool.kind)) +
                           " needs solver: dynamic (contact is part of the explicit dynamics only, not of the static or implicit solvers)");
    }
  }
}

StabilityReport FemEngine::step(const std::vector<ToolInput>& tools, int steps) {
  if (!dynamics_ && !implicit_) throw RuntimeError(options_.where + ": the static FEM solver has no time steps (it solves each frame)");
  check_tools(tools);
  if (implicit_) return step_implicit(tools, steps);
  const double t_next = dynamics_->time() + dynamics_->dt();
  if (holds_.captures(tools)) sync();  // a tool captures the nodes where they are now
  holds_.update_grabs(tools, t_next, u_, false, grab_nodes_, grab_displacements_);
  if (!grab_nodes_.empty()) {
    dynamics_->set_prescribed(grab_nodes_, grab_displacements_);
    had_grab_ = true;
  } else if (had_grab_) {
    dynamics_->clear_prescribed();
    had_grab_ = false;
  }
  // One probe at a time is supported by the dynamics' contact sphere: the first active one.
  std::array<double, 3> centre{0, 0, 0};
  double radius = 0;
  for (const ToolInput& tool : tools) {
    if (tool.kind == ToolKind::probe && tool.active) {
      centre = tool.centre;
      radius = tool.radius_mm;
      break;
    }
  }
  dynamics_->set_contact_sphere(centre, radius);
  instrument_views_.clear();
  for (const ToolInput& tool : tools) {
    if (tool.kind != ToolKind::instrument || !tool.active) continue;
    if (!tool.instrument) throw InputError(options_.where, tool.label, "the instrument has no shape");
    instrument_views_.push_back(instrument_view(*tool.instrument, tool.orientation, tool.centre));
  }
  dynamics_->set_contact_instruments(instrument_views_);
  if (holds_.update_forces(tools, u_, false)) dynamics_->set_external_forces(holds_.nodal_forces());
  try {
    dynamics_->step(steps);
  } catch (const RuntimeError& e) {
    StabilityReport r;
    r.stable = false;
    r.time = dynamics_->time();
    r.message = e.what();
    return r;
  }
  steps_ += steps;
  return {};
}

void FemEngine::equilibrium(const std::vector<ToolInput>& tools, double time) {
  if (dynamics_ || implicit_) throw RuntimeError(options_.where + ": the dynamic FEM solver steps in time (it has no equilibrium solve)");
  check_tools(tools);
  holds_.update_grabs(tools, time, u_, true, grab_nodes_, grab_displacements_);
  holds_.update_forces(tools, u_, true);
  FemLoads loads;
  loads.gravity = options_.gravity;
  loads.forces = holds_.nodal_forces();
  FemStaticResult r;
  if (linear_) {
    r = linear_->solve(grab_nodes_, grab_displacements_, loads);
  } else {
    bc_.prescribed_nodes = grab_nodes_;
    bc_.prescribed_displacements = grab_displacements_;
    r = static_solver_->solve(bc_, loads, solves_ > 0 ? &u_ : nullptr);  // warm start from the previous frame
  }
  if (!r.report.converged) {
    throw RuntimeError(options_.where + ": the static FEM solve at t = " + std::to_string(time) +
                       " s did not converge: relative residual " + std::to_string(r.report.relative_residual) + " after " +
                       std::to_string(r.report.newton_iterations) + " Newton iterations");
  }
  u_ = std::move(r.displacements);
  newton_ = r.report.newton_iterations;
  cg_ = std::accumulate(r.report.cg_iterations.begin(), r.report.cg_iterations.end(), 0);
  steps_ += r.report.newton_iterations;
  static_time_ = time;
  ++solves_;
}

void FemEngine::sync() {
  if (implicit_) {
    u_ = implicit_->displacements();
    return;
  }
  if (!dynamics_) return;
  const auto d = dynamics_->displacements();
  u_.assign(d.begin(), d.end());
}

StabilityReport FemEngine::step_implicit(const std::vector<ToolInput>& tools, int steps) {
  const double t_next = implicit_->time() + implicit_->dt();
  if (holds_.captures(tools)) sync();  // a tool captures the nodes where they are now
  // Captured with the tool where it started (within this step: a frame-long step must not lose the
  // tool's motion over it, as capturing at t_next would).
  holds_.update_grabs(tools, t_next, u_, true, grab_nodes_, grab_displacements_);
  if (!grab_nodes_.empty()) {
    implicit_->set_prescribed(grab_nodes_, grab_displacements_);
  } else {
    implicit_->clear_prescribed();
  }
  if (holds_.update_forces(tools, u_, false)) implicit_->set_external_forces(holds_.nodal_forces());
  try {
    const FemImplicitStepReport r = implicit_->step(steps);
    newton_ += r.newton_iterations;
  } catch (const RuntimeError& e) {
    StabilityReport r;
    r.stable = false;
    r.time = implicit_->time();
    r.message = e.what();
    return r;
  }
  steps_ += steps;
  return {};
}

void FemEngine::positions(std::vector<double>& xyz) const {
  xyz.resize(u_.size());
  for (size_t i = 0; i < u_.size(); ++i) xyz[i] = model_.nodes[i] + u_[i];
}

void FemEngine::surface_vertices(std::vector<float>& xyz) {
  const std::vector<double>& rest = model_.nodes;
  if (surface_.empty()) {
    xyz.resize(u_.size());
    for (size_t i = 0; i < xyz.size(); ++i) xyz[i] = static_cast<float>(rest[i] + u_[i]);
    return;
  }
  if (!quadratic_nodes_.empty()) {
    const std::vector<Real>& rv = surface_.rest_vertices();
    const int64_t nv = surface_.vertex_count();
    xyz.resize(3 * static_cast<size_t>(nv));
#pragma omp parallel for schedule(static) num_threads(cpu::thread_count(options_.threads, static_cast<int32_t>(nv / 1024)))
    for (int64_t v = 0; v < nv; ++v) {
      double d[3] = {0, 0, 0};
      for (int a = 0; a < 10; ++a) {
        const size_t k = 10 * static_cast<size_t>(v) + a;
        const size_t n = static_cast<size_t>(quadratic_nodes_[k]);
        for (int c = 0; c < 3; ++c) d[c] += quadratic_weights_[k] * u_[3 * n + c];
      }
      for (int c = 0; c < 3; ++c) xyz[3 * static_cast<size_t>(v) + c] = static_cast<float>(rv[3 * static_cast<size_t>(v) + c] + d[c]);
    }
    return;
  }
  for (size_t i = 0; i < static_cast<size_t>(model_.node_count()); ++i) {
    positions_.x[i] = static_cast<Real>(rest[3 * i] + u_[3 * i]);
    positions_.y[i] = static_cast<Real>(rest[3 * i + 1] + u_[3 * i + 1]);
    positions_.z[i] = static_cast<Real>(rest[3 * i + 2] + u_[3 * i + 2]);
  }
  surface_.move(positions_, rest_real_, xyz, options_.threads);
}

EngineMetrics FemEngine::metrics() const {
  EngineMetrics m;
  m.kinetic_energy = dynamics_ ? dynamics_->kinetic_energy() : implicit_ ? implicit_->kinetic_energy() : 0.0;
  m.elastic_energy = dynamics_ ? dynamics_->strain_energy() : implicit_ ? implicit_->strain_energy() : fem_strain_energy(model_, u_);
  double max_u = 0;
  for (size_t i = 0; i < u_.size(); i += 3) max_u = std::max(max_u, u_[i] * u_[i] + u_[i + 1] * u_[i + 1] + u_[i + 2] * u_[i + 2]);
  m.max_displacement = std::sqrt(max_u);
  m.extra = {static_cast<double>(newton_), static_cast<double>(cg_)};
  return m;
}

void FemEngine::save_checkpoint() { throw RuntimeError(options_.where + ": the FEM engine does not restart with a halved step"); }
void FemEngine::restart_halved() { throw RuntimeError(options_.where + ": the FEM engine does not restart with a halved step"); }

}  // namespace ctsurg::sim
