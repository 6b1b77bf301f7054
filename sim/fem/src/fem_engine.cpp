#include "ctsurg/sim/fem/fem_engine.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/base/parallel.h"
#include "ctsurg/sim/fem/fem_cutting.h"
#include "ctsurg/sim/fem/fem_element_removal.h"
#include "ctsurg/sim/fem/fem_forces.h"
#include "ctsurg/sim/fem/fem_integrator.h"
#include "ctsurg/sim/fem/fem_local_region.h"
#include "ctsurg/sim/fem/kernels/fem_quadratic_element_impl.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numeric>
#include <utility>

namespace ctsurg::sim {
namespace {

// Per node: the axes a support holds (bit a for axis a; kAllAxes: the whole node). Tools capture the
// nodes not wholly held and act on their free axes (fem_tools.h).
std::vector<uint8_t> held_axes(int32_t nodes, const FemBoundaryConditions& supports) {
  std::vector<uint8_t> axes(static_cast<size_t>(nodes), 0);
  for (const int32_t n : supports.fixed_nodes) {
    if (n < 0 || n >= nodes) throw InputError("fem engine", "fixed", "node " + std::to_string(n) + " out of range");
    axes[static_cast<size_t>(n)] = kAllAxes;
  }
  for (const int32_t c : supports.fixed_components) {
    if (c < 0 || c >= 3 * nodes) throw InputError("fem engine", "fixed", "component " + std::to_string(c) + " out of range");
    axes[static_cast<size_t>(c / 3)] |= static_cast<uint8_t>(1u << (c % 3));
  }
  return axes;
}

// For each surface vertex of `coupling` (slots 0..3: the corners of a tet, as tet_embedding.h ties them),
// the element whose corners those are (#V). InputError(where, "surface", ...) for a vertex tied to no tet.
std::vector<int32_t> surface_elements(const FemModel& model, const SurfaceCoupling& coupling, const std::string& where) {
  const size_t npe = static_cast<size_t>(model.nodes_per_element());
  std::map<std::array<int32_t, 4>, int32_t> element_of;
  for (int32_t e = 0; e < model.tet_count(); ++e) {
    std::array<int32_t, 4> key;
    for (size_t a = 0; a < 4; ++a) key[a] = model.tets[npe * static_cast<size_t>(e) + a];
    std::sort(key.begin(), key.end());
    element_of.emplace(key, e);
  }
  const int64_t nv = coupling.vertex_count();
  std::vector<int32_t> elements(static_cast<size_t>(nv));
  for (int64_t v = 0; v < nv; ++v) {
    std::array<int32_t, 4> key;
    for (size_t a = 0; a < 4; ++a) key[a] = coupling.particles[8 * static_cast<size_t>(v) + a];
    std::sort(key.begin(), key.end());
    const auto it = element_of.find(key);
    if (it == element_of.end()) throw InputError(where, "surface", "vertex " + std::to_string(v) + " is not tied to a tet of the model");
    elements[static_cast<size_t>(v)] = it->second;
  }
  return elements;
}

// For each surface vertex of `coupling` (slots 0..3: the corners of a linear tet, weights: barycentric),
// the quadratic element with those corners and its 10 shape-function values there.
void quadratic_surface(const FemModel& model, const SurfaceCoupling& coupling, std::vector<int32_t>& nodes, std::vector<double>& weights) {
  const std::vector<int32_t> element = surface_elements(model, coupling, "fem engine");
  const int64_t nv = coupling.vertex_count();
  nodes.resize(10 * static_cast<size_t>(nv));
  weights.resize(10 * static_cast<size_t>(nv));
  for (int64_t v = 0; v < nv; ++v) {
    const int32_t* t = &model.tets[10 * static_cast<size_t>(element[static_cast<size_t>(v)])];
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
      holds_(model_, held_axes(model_.node_count(), supports_), options_.where, options_.note),
      u_(model_.nodes.size(), 0.0),
      rest_real_(model_.nodes.begin(), model_.nodes.end()),
      positions_(rest_real_, std::vector<Real>(static_cast<size_t>(model_.node_count()), Real(1))) {
  counts_.nodes = model_.node_count();
  counts_.elements = model_.tet_count();
  const std::vector<uint8_t> held = held_axes(model_.node_count(), supports_);
  counts_.fixed = std::count(held.begin(), held.end(), kAllAxes);
  counts_.partly_fixed = model_.node_count() - counts_.fixed - std::count(held.begin(), held.end(), uint8_t{0});
  supports_.prescribed_nodes.clear();
  supports_.prescribed_displacements.clear();
  if (model_.order == 2 && !surface_.empty()) quadratic_surface(model_, surface_.coupling(), quadratic_nodes_, quadratic_weights_);
  if (options_.solver == FemSolver::dynamic && !supports_.fixed_components.empty()) {
    throw InputError(options_.where, "fixed", "the explicit dynamics fixes whole nodes; fixing some axes needs the static or implicit solver");
  }
  if (options_.solver == FemSolver::dynamic) counts_.critical_dt_s = fem_critical_time_step(model_, options_.safety_factor).critical;
  if (options_.contact.enabled && options_.solver != FemSolver::dynamic) {
    throw InputError(options_.where, "contact", "contact needs solver: dynamic (it is part of the explicit dynamics)");
  }
  if (options_.local_region_mm) {
    const double r = *options_.local_region_mm;
    if (!(r > 0) || !std::isfinite(r)) {
      throw InputError(options_.where, "local_region", "radius_mm must be a positive number of mm (got " + std::to_string(r) + ")");
    }
    if (options_.solver != FemSolver::static_equilibrium) {
      throw InputError(options_.where, "local_region", "a local region needs solver: static (it couples quasi-static solves)");
    }
    if (model_.order != 1) throw InputError(options_.where, "local_region", "a local region needs linear (4-node) tets");
  }
  make_solvers();
  if (options_.contact.enabled) {
    std::vector<int32_t> piece;
    bodies_ = fem_mesh_pieces(model_.tets, model_.node_count(), piece);
    element_body_.resize(static_cast<size_t>(model_.tet_count()));
    for (size_t e = 0; e < element_body_.size(); ++e) element_body_[e] = piece[static_cast<size_t>(model_.tets[static_cast<size_t>(model_.nodes_per_element()) * e])];
  }
}

// The integrator for options_.solver on model_ and supports_ (at the start, and again after a cut split
// nodes or a removal took elements), and without a surface the mesh's boundary faces.
void FemEngine::make_solvers() {
  if (surface_.empty()) {
    const size_t npe = static_cast<size_t>(model_.nodes_per_element());
    std::vector<int32_t> corners;
    corners.reserve(4 * static_cast<size_t>(model_.tet_count()));
    for (size_t e = 0; e < model_.tets.size(); e += npe) corners.insert(corners.end(), model_.tets.begin() + static_cast<std::ptrdiff_t>(e), model_.tets.begin() + static_cast<std::ptrdiff_t>(e + 4));
    boundary_triangles_ = fem_boundary_faces(corners);
  }
  integrator_.reset();  // the old solver's memory goes before the new one's is taken
  integrator_ = make_fem_integrator(model_, supports_, options_, backend_);
}

FemEngine::~FemEngine() = default;

double FemEngine::blade_sweep_mm() const {
  // A quarter of the mean edge: a sweep shorter than that tests every face for little.
  if (model_.order != 1 || model_.tets.empty()) return 0;
  double total = 0;
  int64_t edges = 0;
  for (size_t e = 0; e < model_.tets.size(); e += 4)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) {
        const double* p = &model_.nodes[3 * static_cast<size_t>(model_.tets[e + static_cast<size_t>(a)])];
        const double* q = &model_.nodes[3 * static_cast<size_t>(model_.tets[e + static_cast<size_t>(b)])];
        total += std::sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
        ++edges;
      }
  return 0.25 * total / static_cast<double>(edges);
}

void FemEngine::apply_cuts(const std::vector<ToolInput>& tools) {
  bool any = false;
  for (const ToolInput& tool : tools) any = any || (tool.acts == ToolPrimitive::separate && !tool.sweeps.empty());
  if (!any) return;
  if (!separation_) {
    separation_ = std::make_unique<FemTetSeparation>(model_);
    if (!surface_.empty()) {
      // Each surface vertex's tet and which of its corners each tie is: after a split, the vertex
      // follows the copies its own tet uses.
      const SurfaceCoupling& c = surface_.coupling();
      surface_element_ = surface_elements(model_, c, options_.where);
      surface_corner_.assign(8 * surface_element_.size(), -1);
      for (size_t v = 0; v < surface_element_.size(); ++v)
        for (size_t k = 0; k < 4; ++k)
          for (int a = 0; a < 4; ++a)
            if (model_.tets[4 * static_cast<size_t>(surface_element_[v]) + static_cast<size_t>(a)] == c.particles[8 * v + k])
              surface_corner_[8 * v + k] = a;
    }
  }
  sync();
  std::vector<double> positions(u_.size());
  for (size_t i = 0; i < u_.size(); ++i) positions[i] = model_.nodes[i] + u_[i];
  std::vector<float> vertices;
  if (!surface_.empty()) surface_vertices(vertices);
  std::vector<int32_t> tets = model_.tets, parents;
  const int32_t n0 = model_.node_count();
  for (const ToolInput& tool : tools) {
    if (tool.acts != ToolPrimitive::separate) continue;
    for (const auto& [from, to] : tool.sweeps) {
      for (const Triangle& tri : swept_blade(from, to, tool.blade_edge_mm)) {
        const FemCutResult r = separation_->cut(tets, n0 + static_cast<int32_t>(parents.size()), positions, tri);
        faces_cut_ += r.faces_separated;
        for (const int32_t p : r.new_node_parent) {
          parents.push_back(p);
          for (int c = 0; c < 3; ++c) positions.push_back(positions[3 * static_cast<size_t>(p) + static_cast<size_t>(c)]);
        }
        if (!surface_.empty()) triangles_removed_ += surface_.cut_triangles(tri, vertices);
      }
    }
  }
  if (!parents.empty()) split_nodes(tets, parents, tools);
}

// After a cut: the model with the new nodes (each a copy of its parent: rest position, displacement,
// velocity, support), and every solver rebuilt on it with the state carried over.
void FemEngine::split_nodes(const std::vector<int32_t>& tets, const std::vector<int32_t>& parents, const std::vector<ToolInput>& tools) {
  const int32_t n0 = model_.node_count();
  const auto extend = [&](auto& values) {  // #N x 3 -> (#N + new) x 3, copies of the parents' rows
    for (const int32_t p : parents)
      for (int c = 0; c < 3; ++c) values.push_back(values[3 * static_cast<size_t>(p) + static_cast<size_t>(c)]);
  };
  std::vector<double> nodes = model_.nodes;
  extend(nodes);
  FemModel m = build_fem_model(nodes, tets, model_.materials, model_.element_material);  // a cut keeps the tets (and their materials)
  m.frame_origin = model_.frame_origin;
  // A copy is held as its parent is: whole (fixed_nodes) or in single components (fixed_components).
  std::vector<uint8_t> fixed = held_axes(n0, supports_);
  std::vector<uint8_t> whole(static_cast<size_t>(n0), 0), component(3 * static_cast<size_t>(n0), 0);
  for (const int32_t n : supports_.fixed_nodes) whole[static_cast<size_t>(n)] = 1;
  for (const int32_t c : supports_.fixed_components) component[static_cast<size_t>(c)] = 1;
  for (size_t k = 0; k < parents.size(); ++k) {
    const int32_t id = n0 + static_cast<int32_t>(k), p = parents[k];
    fixed.push_back(fixed[static_cast<size_t>(p)]);
    whole.push_back(whole[static_cast<size_t>(p)]);
    if (whole[static_cast<size_t>(p)]) supports_.fixed_nodes.push_back(id);
    for (int a = 0; a < 3; ++a) {
      component.push_back(component[3 * static_cast<size_t>(p) + static_cast<size_t>(a)]);
      if (component[3 * static_cast<size_t>(p) + static_cast<size_t>(a)]) supports_.fixed_components.push_back(3 * id + a);
    }
  }
  if (options_.solver == FemSolver::static_equilibrium) {
    // A piece the cut freed with no support would make the static problem singular: say so, with the
    // tool and what to use instead.
    std::vector<int32_t> piece;
    const int32_t pieces = fem_mesh_pieces(tets, m.node_count(), piece);
    std::vector<uint8_t> held(static_cast<size_t>(pieces), 0);
    for (int32_t n = 0; n < m.node_count(); ++n)
      if (fixed[static_cast<size_t>(n)] && piece[static_cast<size_t>(n)] >= 0) held[static_cast<size_t>(piece[static_cast<size_t>(n)])] = 1;
    for (int32_t k = 0; k < pieces; ++k) {
      if (held[static_cast<size_t>(k)]) continue;
      std::string label = "tools";
      for (const ToolInput& tool : tools)
        if (tool.acts == ToolPrimitive::separate && !tool.sweeps.empty()) label = tool.label;
      throw InputError(options_.where, label, "the cut frees a piece of the mesh that no support holds; a static solve cannot place it: "
                                              "use solver: dynamic or implicit, or fix a region of that piece");
    }
  }
  // The dynamics' state, carried over.
  FemCarriedState carried = integrator_->carried_state();
  if (!carried.displacements.empty()) extend(carried.displacements);
  if (!carried.previous_displacements.empty()) extend(carried.previous_displacements);
  if (!carried.velocities.empty()) extend(carried.velocities);
  extend(u_);
  model_ = std::move(m);  // the same object: holds_ and the solvers' references stay valid until rebuilt
  holds_.nodes_added(parents);
  rest_real_.assign(model_.nodes.begin(), model_.nodes.end());
  positions_ = ParticleState(rest_real_, std::vector<Real>(static_cast<size_t>(model_.node_count()), Real(1)));
  counts_.nodes = model_.node_count();
  counts_.fixed = std::count(fixed.begin(), fixed.end(), kAllAxes);
  counts_.partly_fixed = m.node_count() - counts_.fixed - std::count(fixed.begin(), fixed.end(), uint8_t{0});
  make_solvers();
  integrator_->restore(carried, u_, holds_.nodal_forces());
  if (!surface_.empty()) {
    std::vector<int32_t> ties = surface_.coupling().particles;
    for (size_t v2 = 0; v2 < surface_element_.size(); ++v2) {
      for (size_t k = 0; k < 8; ++k) {
        const int32_t a = surface_corner_[8 * v2 + k];
        if (a >= 0) ties[8 * v2 + k] = model_.tets[4 * static_cast<size_t>(surface_element_[v2]) + static_cast<size_t>(a)];
      }
    }
    surface_.retie(std::move(ties));
  }
  nodes_split_ += static_cast<int64_t>(parents.size());
  if (options_.note) {
    options_.note("FEM cut: " + std::to_string(parents.size()) + " nodes split (" + std::to_string(model_.node_count()) + " nodes, " +
                  std::to_string(separation_->faces_separated()) + " faces separated so far)");
  }
}

// A remove tool (a cautery) takes the elements inside its tip at its rate (fem_element_removal.h). Its
// budget grows by rate x dt a step while the tip is on (a batch of steps adds them all, taken at the
// batch's start) and is dropped when the tip is off or finds nothing in reach. The model is rebuilt
// without the elements taken, the nodes, the dynamics' state and the step kept; the surface over them
// is opened and closed over the crater (hole_filling.h).
void FemEngine::remove_tissue(const std::vector<ToolInput>& tools, int steps) {
  if (removal_budget_.size() < tools.size()) removal_budget_.resize(tools.size(), 0.0);
  bool any = false;
  for (size_t i = 0; i < tools.size(); ++i) {
    if (tools[i].acts != ToolPrimitive::remove) continue;
    if (tools[i].active) {
      any = true;
    } else {
      removal_budget_[i] = 0;
    }
  }
  if (!any) return;
  sync();
  std::vector<uint8_t> removed(static_cast<size_t>(model_.tet_count()), 0);
  double volume = 0;
  int64_t count = 0;
  std::string label;
  for (size_t i = 0; i < tools.size(); ++i) {
    if (tools[i].acts != ToolPrimitive::remove || !tools[i].active) continue;
    removal_budget_[i] += tools[i].removal_rate_mm3_s * integrator_->dt() * steps;
    const FemElementRemoval r = fem_elements_in_sphere(model_, u_, {tools[i].centre, tools[i].radius_mm}, &removal_budget_[i]);
    for (const int32_t e : r.elements) {
      const double v = model_.rest_volume[static_cast<size_t>(e)];
      if (removed[static_cast<size_t>(e)]) {
        removal_budget_[i] += v;  // another tip took it this step
        continue;
      }
      removed[static_cast<size_t>(e)] = 1;
      volume += v;
      ++count;
      label = tools[i].label;
    }
    if (r.exhausted) removal_budget_[i] = 0;
  }
  if (count == 0) return;
  if (count == model_.tet_count()) throw InputError(options_.where, label, "removes every element of the model");
  // The surface vertices in the elements taken, and every vertex's element in the model to come.
  std::vector<uint8_t> vertex_gone;
  if (!surface_.empty()) {
    if (surface_element_.empty()) surface_element_ = surface_elements(model_, surface_.coupling(), options_.where);
    vertex_gone.assign(surface_element_.size(), 0);
    std::vector<int32_t> new_index(removed.size(), -1);
    int32_t next = 0;
    for (size_t e = 0; e < removed.size(); ++e)
      if (!removed[e]) new_index[e] = next++;
    for (size_t v = 0; v < surface_element_.size(); ++v) {
      const int32_t e = surface_element_[v];
      if (e < 0) continue;
      vertex_gone[v] = removed[static_cast<size_t>(e)];
      surface_element_[v] = new_index[static_cast<size_t>(e)];
    }
  }
  const FemCarriedState carried = integrator_->carried_state();
  options_.dt = integrator_->dt();  // the run's step stays (taking elements away lowers no element's critical step)
  model_ = fem_model_without(model_, removed);  // the same object: holds_ keeps its reference; the node ids stay
  counts_.elements = model_.tet_count();
  make_solvers();
  integrator_->restore(carried, u_, holds_.nodal_forces());
  removed_volume_ += volume;
  if (!vertex_gone.empty()) {
    // The holes the crater opens are closed; the surface's own boundary is the one it had before.
    if (!surface_.close_cuts()) surface_.set_close_cuts(true);
    const int64_t opened = surface_.remove_vertices(vertex_gone);
    triangles_removed_ += opened;
    if (opened > 0) {
      std::vector<float> vertices;
      surface_vertices(vertices);
      surface_.close_cut_holes(vertices);
    }
  }
}

namespace {
constexpr int32_t kMaxBodyMetrics = 16;
}

std::vector<std::pair<std::string, std::string>> FemEngine::extra_metrics() const {
  std::vector<std::pair<std::string, std::string>> names{{"newton_iterations", "1"}, {"cg_iterations", "1"}, {"element_volume", "mm^3"}, {"nodes", "1"}};
  if (integrator_->local_region()) {
    for (const char* n : {"region_nodes", "region_tets", "interface_nodes"}) names.emplace_back(n, "1");
    names.emplace_back("interface_residual", "uN");
  }
  // With contact: the deepest penetration between the surfaces (fem_contact.h) and each body's element
  // volume (up to 16 bodies).
  if (options_.contact.enabled) {
    names.emplace_back("contact_penetration", "mm");
    for (int32_t b = 0; b < std::min(bodies_, kMaxBodyMetrics); ++b) names.emplace_back("body_volume_" + std::to_string(b), "mm^3");
  }
  // A quasi-Newton frame's estimate of its distance from the converged solution (fem_static_solver.h,
  // FemStaticReport::error_estimate_mm): what the live page shows per frame.
  if (reports_solver_error()) names.emplace_back("solver_error_mm", "mm");
  return names;
}

bool FemEngine::reports_solver_error() const {
  return integrator_->quasi_static() && !integrator_->local_region() && options_.newton.nonlinear == FemNonlinearSolve::quasi_newton;
}

double FemEngine::dt() const { return integrator_->dt(); }
double FemEngine::time() const { return integrator_->time(); }

void FemEngine::check_tools(const std::vector<ToolInput>& tools) const {
  for (const ToolInput& tool : tools) {
    switch (tool.acts) {
      case ToolPrimitive::hold:
        if (tool.grip == HoldGrip::volume) {
          if (options_.solver == FemSolver::dynamic) {
            throw InputError(options_.where, tool.label,
                             "grip: volume needs solver: static_equilibrium or implicit (its penalty is stiff: the explicit "
                             "dynamics' critical step would shrink to it); use grip: nodes with solver: dynamic");
          }
          if (options_.local_region_mm) {
            throw InputError(options_.where, tool.label,
                             "grip: volume and a local region are not supported together (the region's solve holds node sets); use grip: nodes");
          }
        }
        break;
      case ToolPrimitive::load:
        break;
      case ToolPrimitive::separate:
        if (model_.order != 1) {
          throw InputError(options_.where, tool.label, "cutting needs linear (4-node) tets; quadratic elements are not cut");
        }
        if (backend_ != Backend::cpu) {
          throw InputError(options_.where, tool.label, "cutting an FEM model runs on the cpu backend only; set backend: cpu");
        }
        break;
      case ToolPrimitive::push_sphere:
      case ToolPrimitive::push_shape:
        if (options_.solver != FemSolver::dynamic) {
          throw InputError(options_.where, tool.label,
                           tool.name +
                               " needs solver: dynamic (contact is part of the explicit dynamics only, not of the static or implicit solvers)");
        }
        break;
      case ToolPrimitive::stitch:
        throw InputError(options_.where, tool.label,
                         tool.name + " runs on the spring models only (kind: spring_grid or explicit_springs); the FEM engine "
                                     "does not stitch yet");
      case ToolPrimitive::remove: {
        // Removing elements rebuilds the model under the explicit dynamics' state (remove_tissue).
        std::string why;
        if (model_.order != 1) why = "needs linear (4-node) tets";
        if (options_.solver != FemSolver::dynamic) why = "needs solver: dynamic (the explicit dynamics carries its state over a removal)";
        if (backend_ != Backend::cpu) why = "runs on the cpu backend only; set backend: cpu";
        if (options_.contact.enabled) why = "and contact together are not supported (the bodies are the mesh's pieces at the start)";
        for (const ToolInput& other : tools)
          if (other.acts == ToolPrimitive::separate) why = "and a blade on one FEM model are not supported (" + other.label + ")";
        if (!why.empty()) throw InputError(options_.where, tool.label, tool.name + " " + why);
        break;
      }
    }
  }
}

StabilityReport FemEngine::step(const std::vector<ToolInput>& tools, int steps) {
  if (integrator_->quasi_static()) throw RuntimeError(options_.where + ": the static FEM solver has no time steps (it solves each frame)");
  check_tools(tools);
  apply_cuts(tools);
  remove_tissue(tools, steps);
  const FemAdvance a = integrator_->advance(holds_, tools, steps, u_);
  if (!a.stability.stable) return a.stability;
  newton_ += a.newton_iterations;  // the implicit dynamics' Newton iterations, cumulative
  steps_ += steps;
  return {};
}

void FemEngine::equilibrium(const std::vector<ToolInput>& tools, double time) {
  if (!integrator_->quasi_static()) throw RuntimeError(options_.where + ": the dynamic FEM solver steps in time (it has no equilibrium solve)");
  check_tools(tools);
  apply_cuts(tools);
  const FemAdvance a = integrator_->equilibrium(holds_, tools, time, solves_ > 0, u_);  // warm start from the previous frame
  newton_ = a.newton_iterations;
  cg_ = a.cg_iterations;
  solver_error_mm_ = a.solver_error_mm;
  steps_ += a.newton_iterations;
  ++solves_;
}

void FemEngine::sync() { integrator_->displacements(u_); }

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

const std::vector<uint8_t>* FemEngine::local_region() const {
  const FemLocalRegionSolver* local = integrator_->local_region();
  return local ? &local->node_region() : nullptr;
}

bool FemEngine::surface_vertex_region(std::vector<uint8_t>& flags) const {
  const FemLocalRegionSolver* local = integrator_->local_region();
  if (!local) return false;
  const std::vector<uint8_t>& nodes = local->node_region();
  const size_t nn = static_cast<size_t>(model_.node_count());
  const bool solved = nodes.size() == nn;  // none before the first solve
  const auto node_flag = [&](int32_t n) { return solved && n >= 0 ? nodes[static_cast<size_t>(n)] : uint8_t{0}; };
  if (surface_.empty()) {
    flags.resize(nn);
    for (size_t i = 0; i < nn; ++i) flags[i] = node_flag(static_cast<int32_t>(i));
    return true;
  }
  // Each vertex's ties are its tet's corners (tet_embedding.h; relinked to a split node's copy after a cut).
  const SurfaceCoupling& c = surface_.coupling();
  const size_t nv = static_cast<size_t>(surface_.vertex_count());
  flags.assign(nv, 0);
  for (size_t v = 0; v < nv; ++v)
    for (size_t k = 0; k < 8; ++k) flags[v] = std::max(flags[v], node_flag(c.particles[8 * v + k]));
  return true;
}

EngineMetrics FemEngine::metrics() const {
  EngineMetrics m;
  m.removed_volume = removed_volume_;
  m.kinetic_energy = integrator_->kinetic_energy();
  m.elastic_energy = integrator_->strain_energy(model_, u_);
  double max_u = 0;
  for (size_t i = 0; i < u_.size(); i += 3) max_u = std::max(max_u, u_[i] * u_[i] + u_[i + 1] * u_[i + 1] + u_[i + 2] * u_[i + 2]);
  m.max_displacement = std::sqrt(max_u);
  // The elements' deformed volume (of their corner tets: exact for linear tets; the tissue's volume
  // whatever a cut did to the surface) and the node count (a cut adds nodes).
  double volume = 0;
  std::vector<double> body_volume(static_cast<size_t>(std::min(bodies_, kMaxBodyMetrics)), 0.0);
  {
    const size_t npe = static_cast<size_t>(model_.nodes_per_element());
    for (size_t e = 0; e < model_.tets.size(); e += npe) {
      double d[3][3];
      const double* p0 = &model_.nodes[3 * static_cast<size_t>(model_.tets[e])];
      const double* u0 = &u_[3 * static_cast<size_t>(model_.tets[e])];
      for (int a = 1; a < 4; ++a) {
        const size_t n = 3 * static_cast<size_t>(model_.tets[e + static_cast<size_t>(a)]);
        for (int c = 0; c < 3; ++c) d[a - 1][c] = model_.nodes[n + static_cast<size_t>(c)] + u_[n + static_cast<size_t>(c)] - p0[c] - u0[c];
      }
      const double v = (d[0][0] * (d[1][1] * d[2][2] - d[1][2] * d[2][1]) - d[0][1] * (d[1][0] * d[2][2] - d[1][2] * d[2][0]) +
                        d[0][2] * (d[1][0] * d[2][1] - d[1][1] * d[2][0])) / 6;
      volume += v;
      if (!body_volume.empty()) {
        const size_t b = static_cast<size_t>(element_body_[e / npe]);
        if (b < body_volume.size()) body_volume[b] += v;
      }
    }
  }
  m.extra = {static_cast<double>(newton_), static_cast<double>(cg_), volume, static_cast<double>(model_.node_count())};
  if (const FemLocalRegionSolver* local = integrator_->local_region()) {
    const FemLocalRegionReport& lr = local->report();
    m.extra.insert(m.extra.end(), {static_cast<double>(lr.region_nodes), static_cast<double>(lr.region_tets),
                                   static_cast<double>(lr.interface_nodes), lr.interface_residual});
  }
  if (options_.contact.enabled) {
    const FemContact* contact = integrator_->contact();
    const std::vector<Real> u(u_.begin(), u_.end());
    m.extra.push_back(contact ? contact->deepest_penetration(model_, u.data()) : 0.0);
    m.extra.insert(m.extra.end(), body_volume.begin(), body_volume.end());
  }
  // Where no quasi-Newton estimate exists (the rest frame before any solve, a frame that went on with
  // Newton, the linear law's condensation): the budget tolerance_mm instead (0 with the relative rule).
  if (reports_solver_error()) m.extra.push_back(std::isfinite(solver_error_mm_) ? solver_error_mm_ : std::max(0.0, options_.newton.tolerance_mm));
  m.springs_cut = faces_cut_;  // the FEM's cuts: faces separated
  m.triangles_removed = triangles_removed_;
  return m;
}

void FemEngine::save_checkpoint() { throw RuntimeError(options_.where + ": the FEM engine does not restart with a halved step"); }
void FemEngine::restart_halved() { throw RuntimeError(options_.where + ": the FEM engine does not restart with a halved step"); }

}  // namespace ctsurg::sim
