#include "fem_newton.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/memory_guard.h"
#include "ctsurg/core/elapsed_seconds.h"
#include "ctsurg/sim/base/parallel.h"
#include "device_conjugate_gradient.h"
#include "fem_cpu_kernels.h"
#include "fem_element_view.h"
#include "fem_rigid_modes.h"
#include "sparse_cholesky.h"

#include <Eigen/IterativeLinearSolvers>

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

namespace ctsurg::sim {
namespace {

constexpr double kForcingMax = 1e-2;  // the inexact Newton forcing term's cap (see newton)
using Clock = std::chrono::steady_clock;

// Eigen's sparse products (CG, the reused factor's CG) run one OpenMP team per product: below ~1e6
// non-zeros a team costs more than it saves, and far more when the cores are shared (measured: 10x
// slower on a loaded 2-core machine). Sets the count for a scope.
class EigenThreads {
 public:
  explicit EigenThreads(int threads) : before_(Eigen::nbThreads()) { Eigen::setNbThreads(threads); }
  ~EigenThreads() { Eigen::setNbThreads(before_); }
  EigenThreads(const EigenThreads&) = delete;
  EigenThreads& operator=(const EigenThreads&) = delete;

 private:
  int before_;
};

// The largest of the last `count` values.
double recent_max(const std::vector<double>& history, std::size_t count) {
  double m = 0;
  for (std::size_t k = history.size() > count ? history.size() - count : 0; k < history.size(); ++k) m = std::max(m, history[k]);
  return m;
}

void check_node(int32_t id, int32_t n, const char* field) {
  if (id < 0 || id >= n) throw InputError("fem static", field, "node id " + std::to_string(id) + " out of range [0, " + std::to_string(n) + ")");
}

}  // namespace

std::string fem_element_text(const FemModel& model, int32_t e) {
  std::ostringstream s;
  s << "element " << e << " (rest centroid";
  double centroid[3] = {0, 0, 0};
  for (int c = 0; c < 3; ++c)
    for (int a = 0; a < 4; ++a) centroid[c] += model.nodes[3 * model.tets[static_cast<std::size_t>(model.nodes_per_element()) * e + a] + c] / 4;
  const auto lps = fem_lps_point(model, centroid);
  for (int c = 0; c < 3; ++c) s << (c ? ", " : " (") << lps[c];
  s << ") mm)";
  return s.str();
}

void validate_fem_static(const FemModel& model, const FemBoundaryConditions& bc, const FemLoads& loads, const FemStaticOptions& o) {
  const char* where = "fem static";
  const int32_t n = model.node_count();
  for (int32_t i : bc.fixed_nodes) check_node(i, n, "fixed_nodes");
  for (int32_t c : bc.fixed_components)
    if (c < 0 || c >= 3 * n) throw InputError(where, "fixed_components", "component " + std::to_string(c) + " out of range [0, 3 #N)");
  for (int32_t i : bc.prescribed_nodes) check_node(i, n, "prescribed_nodes");
  if (bc.prescribed_displacements.size() != 3 * bc.prescribed_nodes.size())
    throw InputError(where, "prescribed_displacements", "expected #G x 3 = " + std::to_string(3 * bc.prescribed_nodes.size()) + " values");
  for (double d : bc.prescribed_displacements)
    if (!std::isfinite(d)) throw InputError(where, "prescribed_displacements", "must be finite");
  if (!loads.forces.empty() && loads.forces.size() != 3 * static_cast<std::size_t>(n))
    throw InputError(where, "forces", "expected #N x 3 = " + std::to_string(3 * n) + " values or none");
  for (double f : loads.forces)
    if (!std::isfinite(f)) throw InputError(where, "forces", "must be finite");
  for (double g : loads.gravity)
    if (!std::isfinite(g)) throw InputError(where, "gravity", "must be finite");
  const std::size_t npe = static_cast<std::size_t>(model.nodes_per_element());
  for (const FemGrip& g : loads.grips) {
    const std::size_t h = g.nodes.size();
    if (g.element_nodes.size() != npe * g.elements.size() || g.matrices.size() != npe * npe * g.elements.size() ||
        g.target.size() != 3 * h || g.captured.size() != 3 * h)
      throw InputError(where, "grips", "a grip's arrays do not match its " + std::to_string(g.elements.size()) + " elements and " +
                                           std::to_string(h) + " nodes");
    for (int32_t e : g.elements)
      if (e < 0 || e >= model.tet_count()) throw InputError(where, "grips", "element " + std::to_string(e) + " out of range");
    for (int32_t i : g.nodes) check_node(i, n, "grips");
    for (int32_t k : g.element_nodes)
      if (k < 0 || static_cast<std::size_t>(k) >= h) throw InputError(where, "grips", "a local node index out of range");
    for (double v : g.matrices)
      if (!std::isfinite(v)) throw InputError(where, "grips", "a grip's matrix must be finite");
    for (double v : g.target)
      if (!std::isfinite(v)) throw InputError(where, "grips", "a grip's target must be finite");
  }
  if (!(o.residual_tolerance > 0 && o.residual_tolerance < 1)) throw InputError(where, "residual_tolerance", "must be in (0, 1)");
  if (!(o.displacement_tolerance > 0 && o.displacement_tolerance < 1)) throw InputError(where, "displacement_tolerance", "must be in (0, 1)");
  if (!(o.cg_tolerance > 0 && o.cg_tolerance < 1)) throw InputError(where, "cg_tolerance", "must be in (0, 1)");
  if (o.max_newton_iterations < 1) throw InputError(where, "max_newton_iterations", "must be >= 1");
  if (o.load_steps < 1 || o.load_steps > 1 << 20) throw InputError(where, "load_steps", "must be in [1, 2^20]");
  if (o.max_halvings < 0 || o.max_halvings > 30) throw InputError(where, "max_halvings", "must be in [0, 30]");
  if (o.max_line_search < 0 || o.max_line_search > 30) throw InputError(where, "max_line_search", "must be in [0, 30]");
  if (o.cg_max_iterations < 0) throw InputError(where, "cg_max_iterations", "must be >= 0");
  if (o.threads < 0) throw InputError(where, "threads", "must be >= 0");
  if (!(std::isfinite(o.tolerance_mm) && o.tolerance_mm >= 0)) throw InputError(where, "tolerance_mm", "must be finite and >= 0 (0: the relative tolerances)");
  if (o.direct_max_bytes < 0) throw InputError(where, "direct_max_bytes", "must be >= 0 (0: half the memory available)");
  if (o.reuse_cg_iterations < 0 || o.reuse_cg_iterations > 1000) throw InputError(where, "reuse_cg_iterations", "must be in [0, 1000]");
  if (o.lbfgs_history < 1 || o.lbfgs_history > 50) throw InputError(where, "lbfgs_history", "must be in [1, 50]");
  if (o.max_quasi_newton_iterations < 1 || o.max_quasi_newton_iterations > 100000)
    throw InputError(where, "max_quasi_newton_iterations", "must be in [1, 100000]");
  if (!o.initial_displacements.empty() && o.initial_displacements.size() != 3 * static_cast<std::size_t>(n))
    throw InputError(where, "initial_displacements", "expected #N x 3 = " + std::to_string(3 * n) + " values or none");
  for (double d : o.initial_displacements)
    if (!std::isfinite(d)) throw InputError(where, "initial_displacements", "must be finite");
}

FemNewton::FemNewton(const FemModel& model, const FemStaticOptions& options, DeviceConjugateGradient* device_cg, const char* where)
    : m_(model),
      o_(options),
      device_cg_(device_cg),
      where_(where),
      threads_(options.threads > 0 ? options.threads : cpu::thread_count(0, model.tet_count())) {
  const int32_t n = model.node_count();
  diag_ = fem_bounding_diagonal(model);
  target_.assign(3 * static_cast<std::size_t>(n), 0.0);
  external_.assign(3 * static_cast<std::size_t>(n), 0.0);
  el_ = fem_element_view(model);
  npe_ = model.nodes_per_element();
  ne_ = 3 * npe_;
  corner_.resize(static_cast<std::size_t>(ne_) * static_cast<std::size_t>(model.tet_count()));
  forces_.resize(3 * static_cast<std::size_t>(n));
  check_allocation(static_cast<uint64_t>(model.tet_count()), static_cast<uint64_t>(ne_ * ne_) * sizeof(double), where_, "the element tangents");
  kbuf_.resize(static_cast<std::size_t>(ne_ * ne_) * static_cast<std::size_t>(model.tet_count()));
}

FemNewton::~FemNewton() = default;

void FemNewton::set_held(const std::vector<uint8_t>& held, const std::vector<double>& target) {
  const int32_t n = m_.node_count();
  std::vector<uint8_t> h = held;
  // Inertia makes the system definite, and so does a grip (a spring to the tool over a volume).
  if (terms_.mass == 0 && grips_.empty()) check_rigid_modes(m_, h, diag_, where_.c_str());
  for (int32_t i = 0; i < n; ++i)  // nodes without tets have no stiffness: held where they are
    if (m_.node_offsets[i + 1] == m_.node_offsets[i]) h[3 * i] = h[3 * i + 1] = h[3 * i + 2] = 1;
  target_ = target;
  if (h == held_ && k_.rows() > 0) return;  // same held set: the pattern and the analysis stay
  held_ = std::move(h);
  build_system();
}

void FemNewton::set_external(const std::vector<double>& external) {
  external_ = external;
  last_s_ = NAN;
}

void FemNewton::set_grips(const std::vector<FemGrip>& grips) {
  bool same = grips.size() == grips_.size();
  for (std::size_t g = 0; same && g < grips.size(); ++g)
    same = grips[g].elements == grips_[g].elements && grips[g].matrices == grips_[g].matrices;
  grips_ = grips;
  last_s_ = NAN;
  if (same) return;
  factor_current_ = false;
  rest_factor_ = false;
  index_grips();
}

void FemNewton::index_grips() {
  grip_slots_.clear();
  if (k_.rows() == 0) return;  // build_system indexes them
  const int* ip = k_.innerIndexPtr();
  const int* op = k_.outerIndexPtr();
  for (const FemGrip& g : grips_)
    for (std::size_t k = 0; k < g.elements.size(); ++k) {
      const int32_t* local = &g.element_nodes[static_cast<std::size_t>(npe_) * k];
      const double* mk = &g.matrices[static_cast<std::size_t>(npe_ * npe_) * k];
      for (int a = 0; a < npe_; ++a)
        for (int b = 0; b < npe_; ++b)
          for (int c = 0; c < 3; ++c) {
            const int32_t row = free_index_[3 * static_cast<std::size_t>(g.nodes[static_cast<std::size_t>(local[a])]) + c];
            const int32_t col = free_index_[3 * static_cast<std::size_t>(g.nodes[static_cast<std::size_t>(local[b])]) + c];
            if (row < 0 || col < 0) continue;
            const int* p = std::lower_bound(ip + op[row], ip + op[row + 1], col);
            grip_slots_.emplace_back(p - ip, mk[npe_ * a + b]);
          }
    }
}

void FemNewton::set_terms(FemNewtonTerms terms) {
  // The tangent's coefficients change with the step length, and K_n with every step under stiffness damping.
  if (terms.mass != terms_.mass || terms.stiffness_damping != 0 || terms_.stiffness_damping != 0) factor_current_ = false;
  if (terms.mass != rest_mass_ || terms.stiffness_damping != rest_damping_) rest_factor_ = false;
  terms_ = std::move(terms);
  damping_ready_ = false;
  last_s_ = NAN;
  if (!terms_.gradient_origin.empty()) {
    origin_energy_.resize(static_cast<std::size_t>(m_.tet_count()));
    cpu::fem_strain_energy(el_, terms_.gradient_origin.data(), origin_energy_.data(), threads_);
  }
}

// forces_ (the internal forces at w) with each element's discrete-gradient correction (fem_newton.h);
// serial in element order: deterministic. end_energy_ is +inf for an element inverted at u_1 = 2 w - u_0.
void FemNewton::discrete_gradient(const std::vector<double>& w) {
  const std::vector<double>& u0 = terms_.gradient_origin;
  end_u_.resize(w.size());
  for (std::size_t d = 0; d < w.size(); ++d) end_u_[d] = 2 * w[d] - u0[d];
  end_energy_.resize(static_cast<std::size_t>(m_.tet_count()));
  cpu::fem_strain_energy(el_, end_u_.data(), end_energy_.data(), threads_);
  gradient_coefficient_.assign(static_cast<std::size_t>(m_.tet_count()), 0.0);
  for (int32_t e = 0; e < m_.tet_count(); ++e) {
    const int32_t* v = &m_.tets[static_cast<std::size_t>(npe_) * e];
    const double* f = &corner_[static_cast<std::size_t>(ne_) * e];
    double delta[30], dd = 0, fd = 0;
    for (int c = 0; c < ne_; ++c) {
      const std::size_t d = 3 * static_cast<std::size_t>(v[c / 3]) + c % 3;
      delta[c] = end_u_[d] - u0[d];
      dd += delta[c] * delta[c];
      fd += f[c] * delta[c];
    }
    if (!(dd > 1e-300) || !std::isfinite(end_energy_[e])) continue;
    // The numerator is third order in D: below the round-off of its terms it is noise, which |D|^2 would
    // amplify (an element that hardly moves), and the correction is left out.
    const double numerator = end_energy_[e] - origin_energy_[e] + fd;
    if (std::abs(numerator) <= 1e-12 * (std::abs(end_energy_[e]) + std::abs(origin_energy_[e]) + std::abs(fd))) continue;
    const double coefficient = numerator / dd;
    gradient_coefficient_[static_cast<std::size_t>(e)] = coefficient;
    for (int c = 0; c < ne_; ++c) forces_[3 * static_cast<std::size_t>(v[c / 3]) + c % 3] -= coefficient * delta[c];
  }
}

void FemNewton::build_system() {
  const int32_t n = m_.node_count(), t = m_.tet_count();
  free_index_.assign(3 * static_cast<std::size_t>(n), -1);
  free_component_.clear();
  for (int32_t d = 0; d < 3 * n; ++d)
    if (!held_[d]) {
      free_index_[d] = static_cast<int32_t>(free_component_.size());
      free_component_.push_back(d);
    }
  const int32_t free_count = static_cast<int32_t>(free_component_.size());
  // Pattern: rows of the free components, columns of the free components of the node's neighbours.
  std::vector<std::vector<int32_t>> neighbours(n);
  for (int32_t e = 0; e < t; ++e)
    for (int a = 0; a < npe_; ++a)
      for (int b = 0; b < npe_; ++b) neighbours[m_.tets[npe_ * e + a]].push_back(m_.tets[npe_ * e + b]);
  std::vector<int> outer(free_count + 1, 0);
  std::vector<int> inner;
  for (int32_t i = 0; i < n; ++i) {
    auto& nb = neighbours[i];
    std::sort(nb.begin(), nb.end());
    nb.erase(std::unique(nb.begin(), nb.end()), nb.end());
    for (int a = 0; a < 3; ++a) {
      const int32_t row = free_index_[3 * i + a];
      if (row < 0) continue;
      for (int32_t j : nb)
        for (int b = 0; b < 3; ++b)
          if (free_index_[3 * j + b] >= 0) inner.push_back(free_index_[3 * j + b]);
      outer[row + 1] = static_cast<int>(inner.size());
    }
  }
  const int64_t nnz = static_cast<int64_t>(inner.size());
  std::vector<double> zeros(nnz, 0.0);
  k_ = Eigen::Map<const SpMat>(free_count, free_count, nnz, outer.data(), inner.data(), zeros.data());
  // Element entry -> non-zero, then grouped per non-zero (counting sort: contributions in element order).
  const std::size_t ne2 = static_cast<std::size_t>(ne_ * ne_);
  check_allocation(static_cast<uint64_t>(t), 2 * ne2 * sizeof(int64_t), where_, "the assembly map");
  std::vector<int64_t> slot(ne2 * static_cast<std::size_t>(t), -1);
  std::vector<int64_t> count(nnz + 1, 0);
  const int* ip = k_.innerIndexPtr();
  const int* op = k_.outerIndexPtr();
  for (int32_t e = 0; e < t; ++e)
    for (int r = 0; r < ne_; ++r) {
      const int32_t row = free_index_[3 * m_.tets[npe_ * e + r / 3] + r % 3];
      if (row < 0) continue;
      for (int c = 0; c < ne_; ++c) {
        const int32_t col = free_index_[3 * m_.tets[npe_ * e + c / 3] + c % 3];
        if (col < 0) continue;
        const int* p = std::lower_bound(ip + op[row], ip + op[row + 1], col);
        const int64_t z = p - ip;
        slot[ne2 * static_cast<std::size_t>(e) + static_cast<std::size_t>(ne_ * r + c)] = z;
        ++count[z + 1];
      }
    }
  for (int64_t z = 0; z < nnz; ++z) count[z + 1] += count[z];
  contrib_offsets_ = count;
  contrib_.resize(count[nnz]);
  std::vector<int64_t> fill(count.begin(), count.end() - 1);
  for (std::size_t k = 0; k < slot.size(); ++k)
    if (slot[k] >= 0) contrib_[fill[slot[k]]++] = static_cast<int64_t>(k);
  diagonal_.resize(free_count);
  for (int32_t row = 0; row < free_count; ++row) diagonal_[row] = std::lower_bound(ip + op[row], ip + op[row + 1], row) - ip;
  index_grips();
  // The linear solves: direct while the factor fits (after its analysis: the ordering says how big).
  factor_current_ = false;
  rest_factor_ = false;
  direct_ = false;
  cholesky_.reset();
  if (o_.linear_solve != FemLinearSolve::iterative && free_count > 0 &&
      !(o_.linear_solve == FemLinearSolve::automatic && device_cg_ != nullptr)) {
    auto chol = std::make_unique<SparseCholesky>(where_);
    chol->analyze(free_count, op, ip);
    const int64_t limit = o_.direct_max_bytes > 0 ? o_.direct_max_bytes : static_cast<int64_t>(available_memory_bytes() / 2);
    if (o_.linear_solve == FemLinearSolve::direct || chol->factor_bytes() <= limit) {
      cholesky_ = std::move(chol);
      direct_ = true;
    }
  }
}

int64_t FemNewton::factor_bytes() const { return cholesky_ ? cholesky_->factor_bytes() : 0; }

std::string FemNewton::node_of_column(int64_t column) const {
  if (column < 0 || column >= static_cast<int64_t>(free_component_.size())) return "column " + std::to_string(column);
  const int32_t d = free_component_[static_cast<std::size_t>(column)];
  std::ostringstream s;
  const auto p = fem_lps_point(m_, &m_.nodes[3 * (d / 3)]);
  s << "node " << d / 3 << " (rest " << p[0] << ", " << p[1] << ", " << p[2]
    << " mm), axis " << "xyz"[d % 3];
  return s.str();
}

int32_t FemNewton::forces(const std::vector<double>& u, double s, std::vector<double>& out) {
  const int32_t inverted = cpu::fem_forces(el_, m_.node_offsets.data(), m_.node_corners.data(), m_.node_count(), u.data(),
                                           corner_.data(), forces_.data(), threads_);
  int32_t inverted_end = -1;
  if (!terms_.gradient_origin.empty() && inverted < 0) {
    discrete_gradient(u);
    for (int32_t e = 0; e < m_.tet_count() && inverted_end < 0; ++e)  // an element inverted at the step's end
      if (!std::isfinite(end_energy_[static_cast<std::size_t>(e)])) inverted_end = e;
  }
  out.resize(u.size());
  for (std::size_t d = 0; d < u.size(); ++d) out[d] = forces_[d] + s * external_[d];
  for (const FemGrip& g : grips_) fem_grip_add_forces(m_, g, u.data(), s, out.data());
  if (terms_.mass != 0) {
    for (std::size_t d = 0; d < u.size(); ++d) out[d] -= terms_.mass * m_.node_mass[d / 3] * (u[d] - terms_.inertia_target[d]);
  }
  if (terms_.stiffness_damping != 0 && damping_ready_) {
    damping_product(u, damping_kw_);
    for (std::size_t d = 0; d < u.size(); ++d) out[d] -= terms_.stiffness_damping * damping_kw_[d];
  }
  return inverted >= 0 ? inverted : inverted_end;
}

// K_n (u - u_n) from the kept element matrices (serial, in element order: deterministic).
void FemNewton::damping_product(const std::vector<double>& u, std::vector<double>& kw) const {
  kw.assign(u.size(), 0.0);
  for (int32_t e = 0; e < m_.tet_count(); ++e) {
    const int32_t* v = &m_.tets[static_cast<std::size_t>(npe_) * e];
    double w[30];
    for (int c = 0; c < ne_; ++c) w[c] = u[3 * v[c / 3] + c % 3] - terms_.damping_origin[3 * v[c / 3] + c % 3];
    const double* k = &kbuf_n_[static_cast<std::size_t>(ne_ * ne_) * e];
    for (int r = 0; r < ne_; ++r) {
      double sum = 0;
      for (int c = 0; c < ne_; ++c) sum += k[ne_ * r + c] * w[c];
      kw[3 * v[r / 3] + r % 3] += sum;
    }
  }
}

double FemNewton::energy(const std::vector<double>& u, double s) {
  element_energy_.resize(static_cast<std::size_t>(m_.tet_count()));
  double e = cpu::fem_strain_energy(el_, u.data(), element_energy_.data(), threads_);
  if (!std::isfinite(e)) return HUGE_VAL;
  for (std::size_t d = 0; d < u.size(); ++d) e -= s * external_[d] * u[d];
  for (const FemGrip& g : grips_) e += fem_grip_energy(m_, g, u.data(), s);
  if (terms_.mass != 0) {
    for (std::size_t d = 0; d < u.size(); ++d) {
      const double g = u[d] - terms_.inertia_target[d];
      e += 0.5 * terms_.mass * m_.node_mass[d / 3] * g * g;
    }
  }
  if (terms_.stiffness_damping != 0 && damping_ready_) {  // c_b/2 (u - u_n) . K_n (u - u_n)
    damping_product(u, damping_kw_);
    double wkw = 0;
    for (std::size_t d = 0; d < u.size(); ++d) wkw += (u[d] - terms_.damping_origin[d]) * damping_kw_[d];
    e += 0.5 * terms_.stiffness_damping * wkw;
  }
  return e;
}

// r on the free components; returns the lowest inverted element or -1.
int32_t FemNewton::residual(const std::vector<double>& u, double s, Eigen::VectorXd& r) {
  const int32_t inverted = forces(u, s, all_forces_);
  last_u_ = u;
  last_s_ = inverted < 0 ? s : NAN;
  r.resize(static_cast<Eigen::Index>(free_component_.size()));
  for (std::size_t k = 0; k < free_component_.size(); ++k) r[static_cast<Eigen::Index>(k)] = all_forces_[free_component_[k]];
  return inverted;
}

bool FemNewton::needs_reference() const {
  return !(o_.nonlinear == FemNonlinearSolve::quasi_newton && direct_ && o_.tolerance_mm > 0 && !free_component_.empty() && has_potential());
}

bool FemNewton::last_forces(const std::vector<double>& u, double s, std::vector<double>& out) const {
  if (!(s == last_s_) || u != last_u_ || all_forces_.size() != u.size()) return false;
  out = all_forces_;
  return true;
}

double FemNewton::reference_residual() {
  std::vector<double> u(target_.size(), 0.0);
  for (std::size_t d = 0; d < u.size(); ++d)
    if (held_[d]) u[d] = target_[d];
  Eigen::VectorXd r;
  residual(u, 1.0, r);
  return r.norm();
}

// K_n, the tangent at the damping origin u_n (its element matrices, kept for the step).
void FemNewton::damping_tangent() {
  kbuf_n_.resize(kbuf_.size());
  cpu::fem_stiffness(el_, terms_.damping_origin.data(), kbuf_n_.data(), threads_, o_.projection != FemTangentProjection::never);
  damping_ready_ = true;
  last_s_ = NAN;  // forces() has the damping term from now on
}

void FemNewton::gather_system(const std::vector<double>& kbuf, double scale, const std::vector<double>* kbuf_n, double cb) {
  double* values = k_.valuePtr();
  const int64_t nnz = k_.nonZeros();
  const int64_t* off = contrib_offsets_.data();
  const int64_t* con = contrib_.data();
  const double* kb = kbuf.data();
  const double* kn = kbuf_n != nullptr ? kbuf_n->data() : nullptr;
#pragma omp parallel for schedule(static) num_threads(threads_)
  for (int64_t z = 0; z < nnz; ++z) {
    double v = 0;
    for (int64_t c = off[z]; c < off[z + 1]; ++c) v += kn ? kb[con[c]] + cb * kn[con[c]] : kb[con[c]];
    values[z] = scale * v;
  }
  if (terms_.mass != 0) {
    for (std::size_t k = 0; k < free_component_.size(); ++k) values[diagonal_[k]] += terms_.mass * m_.node_mass[free_component_[k] / 3];
  }
  for (const auto& [z, v] : grip_slots_) values[z] += v;
  double sum = 0;
  for (const int64_t z : diagonal_) sum += values[z];
  mean_diagonal_ = diagonal_.empty() ? 1.0 : std::max(sum / static_cast<double>(diagonal_.size()), 1e-300);
}

int32_t FemNewton::assemble(const std::vector<double>& u, bool project) {
  if (terms_.stiffness_damping != 0 && !damping_ready_) damping_tangent();
  assembled_at_ = &u;
  const int32_t inverted = cpu::fem_stiffness(el_, u.data(), kbuf_.data(), threads_, project);
  if (!terms_.gradient_origin.empty() && gradient_coefficient_.size() == static_cast<std::size_t>(m_.tet_count())) {
    // The discrete gradient's leading-order tangent, from the last forces() (at this u): d(c_e D_e)/dw =
    // 2 c_e (I - 2 D^ D^T) (D^ = D_e / |D_e|; the derivative of the numerator is of higher order), its
    // positive part kept (the factor needs a definite tangent): 2 c_e (I - D^ D^T) for c_e > 0, -2 c_e D^ D^T
    // for c_e < 0.
    for (int32_t e = 0; e < m_.tet_count(); ++e) {
      const double c = gradient_coefficient_[static_cast<std::size_t>(e)];
      if (c == 0) continue;
      const int32_t* v = &m_.tets[static_cast<std::size_t>(npe_) * e];
      double delta[30], dd = 0;
      for (int k = 0; k < ne_; ++k) {
        const std::size_t d = 3 * static_cast<std::size_t>(v[k / 3]) + k % 3;
        delta[k] = end_u_[d] - terms_.gradient_origin[d];
        dd += delta[k] * delta[k];
      }
      double* k = &kbuf_[static_cast<std::size_t>(ne_ * ne_) * e];
      for (int a = 0; a < ne_; ++a)
        for (int b = 0; b < ne_; ++b)
          k[ne_ * a + b] += c > 0 ? 2 * c * ((a == b ? 1.0 : 0.0) - delta[a] * delta[b] / dd) : -2 * c * delta[a] * delta[b] / dd;
    }
  }
  gather_system(kbuf_, 1.0, terms_.stiffness_damping != 0 ? &kbuf_n_ : nullptr, terms_.stiffness_damping);
  // The linear law's tangent does not depend on u: a factor of it stays current (set_terms and
  // build_system say when its coefficients or pattern change).
  if (!m_.every_law(FemLaw::linear)) factor_current_ = false;
  return inverted;
}

int FemNewton::solve_iterative(const Eigen::VectorXd& b, Eigen::VectorXd& du, double tolerance) {
  if (device_cg_ != nullptr) {
    const auto rows = static_cast<int32_t>(k_.rows());
    if (!device_cg_->has_pattern()) device_cg_->set_pattern(rows, k_.outerIndexPtr(), k_.innerIndexPtr());
    device_cg_->set_values(k_.valuePtr());
    du.resize(rows);
    const int64_t max_iterations = o_.cg_max_iterations > 0 ? o_.cg_max_iterations : 2 * static_cast<int64_t>(rows);
    return static_cast<int>(device_cg_->solve(b.data(), du.data(), tolerance, max_iterations).iterations);
  }
  const auto run = [&](auto& cg) {
    cg.setTolerance(tolerance);
    if (o_.cg_max_iterations > 0) cg.setMaxIterations(o_.cg_max_iterations);
    cg.compute(k_);
    du = cg.solve(b);
    return static_cast<int>(cg.iterations());
  };
  if (o_.preconditioner == FemPreconditioner::diagonal) {
    Eigen::ConjugateGradient<SpMat, Eigen::Lower | Eigen::Upper, Eigen::DiagonalPreconditioner<double>> cg;
    return run(cg);
  }
  Eigen::ConjugateGradient<SpMat, Eigen::Lower | Eigen::Upper, Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::AMDOrdering<int>>> cg;
  return run(cg);
}

// Direct: the kept factor preconditions CG on the current tangent while that converges within
// reuse_cg_iterations (to the relative `tolerance`, or with tolerance_mm to a tenth of it in the step);
// otherwise (or with no factor yet) the tangent is factorised and solved exactly. Returns the CG
// iterations (0 for a fresh factor's exact solve).
int FemNewton::solve_direct(const Eigen::VectorXd& b, Eigen::VectorXd& du, double tolerance, FemStaticReport& rep) {
  const Eigen::Index n = b.size();
  du.setZero(n);
  if (n == 0) return 0;
  const double bnorm = b.norm();
  if (bnorm == 0) return 0;
  if (cholesky_->factorized() && !factor_current_ && o_.reuse_cg_iterations > 0) {
    // Preconditioned CG, the old factor as M^-1 (Saad, Iterative Methods, algorithm 9.1).
    Eigen::VectorXd r = b, z(n), p(n), q(n);
    cholesky_->solve(r.data(), z.data());
    p = z;
    double rz = r.dot(z);
    const double goal = tolerance * bnorm;
    for (int it = 1; it <= o_.reuse_cg_iterations; ++it) {
      q.noalias() = k_ * p;
      const double pq = p.dot(q);
      if (!(pq > 0)) break;
      const double alpha = rz / pq;
      du += alpha * p;
      r -= alpha * q;
      if (r.norm() <= goal) return it;
      cholesky_->solve(r.data(), z.data());
      // With the stopping rule in mm, the step needs no more digits than a tenth of the budget: the
      // preconditioned residual z = M^-1 r estimates the step's remaining error (M is near K).
      if (o_.tolerance_mm > 0 && z.lpNorm<Eigen::Infinity>() <= 0.1 * o_.tolerance_mm) return it;
      const double rz_next = r.dot(z);
      p = z + (rz_next / rz) * p;
      rz = rz_next;
    }
    du.setZero(n);  // too slow: refactorise below
  }
  if (!factor_current_) {
    int64_t failed = cholesky_->factorize(k_.valuePtr());
    rest_factor_ = false;
    ++rep.factorizations;
    rep.factor_bytes = cholesky_->factor_bytes();
    if (failed >= 0 && !projecting_ && o_.projection == FemTangentProjection::when_needed &&
        m_.any_indefinite_tangent()) {
      // The exact tangent is indefinite here: project its elements, for the rest of this solve.
      projecting_ = true;
      assemble(*assembled_at_, true);
      failed = cholesky_->factorize(k_.valuePtr());
      ++rep.factorizations;
    }
    if (failed >= 0) {
      throw RuntimeError(where_ + ": the tangent stiffness is not positive definite at " + node_of_column(failed) +
                         " (an element near it is degenerate, or the held components leave that part of the mesh free "
                         "to move rigidly)");
    }
    factor_current_ = true;
  }
  cholesky_->solve(b.data(), du.data());
  return 0;
}

int FemNewton::solve_linear(const Eigen::VectorXd& b, Eigen::VectorXd& du, double tolerance, FemStaticReport& rep) {
  rep.direct = direct_;
  return direct_ ? solve_direct(b, du, tolerance, rep) : solve_iterative(b, du, tolerance);
}

// gap = s target - u on the held components (0 elsewhere); returns whether any is non-zero.
bool FemNewton::held_gap(const std::vector<double>& u, double s, std::vector<double>& gap) const {
  bool any = false;
  for (std::size_t d = 0; d < u.size(); ++d) {
    gap[d] = held_[d] ? s * target_[d] - u[d] : 0.0;
    any = any || gap[d] != 0;
  }
  return any;
}

// b = r - J_fh gap on the free components, J_fh from the element matrices of the last assembly (and
// the damping tangent); serial, in element order: deterministic. Only elements with a moving held
// corner contribute.
void FemNewton::lift(const std::vector<double>& gap, Eigen::VectorXd& b, const std::vector<double>& kbuf, double scale,
                     const std::vector<double>* kbuf_n, double cb) const {
  const int32_t t = m_.tet_count();
  for (int32_t e = 0; e < t; ++e) {
    const int32_t* v = &m_.tets[static_cast<std::size_t>(npe_) * e];
    double g[30];
    bool moving = false;
    for (int c = 0; c < ne_; ++c) {
      g[c] = gap[3 * v[c / 3] + c % 3];
      moving = moving || g[c] != 0;
    }
    if (!moving) continue;
    const std::size_t ne2 = static_cast<std::size_t>(ne_ * ne_);
    const double* k = &kbuf[ne2 * e];
    const double* kn = kbuf_n != nullptr ? &(*kbuf_n)[ne2 * e] : nullptr;
    for (int r = 0; r < ne_; ++r) {
      const int32_t row = free_index_[3 * v[r / 3] + r % 3];
      if (row < 0) continue;
      double kg = 0;
      for (int c = 0; c < ne_; ++c) kg += (kn ? scale * k[ne_ * r + c] + cb * kn[ne_ * r + c] : scale * k[ne_ * r + c]) * g[c];
      b[row] -= kg;
    }
  }
  if (grips_.empty()) return;
  grip_scratch_.assign(gap.size(), 0.0);
  for (const FemGrip& g : grips_) fem_grip_add_product(m_, g, gap.data(), grip_scratch_.data());
  for (std::size_t d = 0; d < gap.size(); ++d)
    if (free_index_[d] >= 0) b[free_index_[d]] -= grip_scratch_[d];
}

FemNewton::LineSearch FemNewton::line_search(const std::vector<double>& u, const Eigen::VectorXd& du, const std::vector<double>& gap,
                                             bool lifting, double s, double bar, double slope, bool accept_any, bool accept_full,
                                             bool secant, std::vector<double>& trial, Eigen::VectorXd& r_trial) {
  LineSearch ls;
  double e0 = NAN;
  double next_alpha = 0.5;
  for (int k = 0; k <= o_.max_line_search; ++k, ls.alpha = next_alpha) {
    next_alpha = 0.5 * ls.alpha;
    trial = u;
    for (std::size_t c = 0; c < free_component_.size(); ++c) trial[free_component_[c]] += ls.alpha * du[static_cast<Eigen::Index>(c)];
    if (lifting) {
      for (std::size_t d = 0; d < u.size(); ++d)
        if (held_[d]) trial[d] = ls.alpha == 1 ? s * target_[d] : u[d] + ls.alpha * gap[d];  // exact at alpha = 1
    }
    ls.inverted = residual(trial, s, r_trial);
    if (ls.inverted >= 0) continue;
    if (lifting || r_trial.norm() < bar || accept_any || (accept_full && ls.alpha == 1)) {
      ls.accepted = true;
      return ls;
    }
    if (secant && slope > 0 && !lifting) {
      const double rising = -r_trial.dot(du);  // dE/dalpha at the trial: past the minimum along du when > 0
      if (rising > 0) next_alpha = ls.alpha * std::clamp(slope / (slope + rising), 0.1, 0.5);
    }
    if (slope > 0 && has_potential()) {  // a descent direction of the potential: Armijo's sufficient decrease
      if (std::isnan(e0)) e0 = energy(u, s);
      if (energy(trial, s) <= e0 - 1e-4 * ls.alpha * slope) {
        ls.accepted = true;
        return ls;
      }
    }
  }
  return ls;
}

// Newton at load factor s from u, whose held components may still sit at an earlier factor's values.
// While they do (a non-zero gap), an iteration is a lifted (consistent) predictor: the held components
// move to their targets and the free ones follow through the tangent, J_ff du_f = r_f - J_fh gap, so a
// grab's displacement spreads over the mesh in one linear step instead of shearing the elements next
// to the grabbed nodes; it takes the longest step alpha = 1, 1/2, ... that inverts no element (no
// residual test: the residual at the old held values is not comparable). Then plain Newton iterations
// with the backtracking line search on ||r||.
bool FemNewton::newton(std::vector<double>& u, double s, FemStaticReport& rep, std::string& failure) {
  // The stiffness damping's K_n before the first residual, so that every residual has its term.
  if (terms_.stiffness_damping != 0 && !damping_ready_) damping_tangent();
  // Quasi-Newton's line search needs the potential: with a discrete gradient (the midpoint scheme) Newton.
  if (o_.nonlinear == FemNonlinearSolve::quasi_newton && direct_ && !free_component_.empty() && has_potential()) {
    if (quasi_newton(u, s, rep, failure)) return true;
    ++rep.quasi_newton_fallbacks;
    rep.error_estimate_mm = NAN;  // Newton's own (quadratic near the end) is not estimated
  }
  // Left out for quasi-Newton with the millimetre rule (needs_reference): Newton's forcing term needs it.
  if (std::isnan(rep.reference_residual)) rep.reference_residual = reference_residual();
  return newton_iterations(u, s, rep, failure);
}

bool FemNewton::first_residual(const std::vector<double>& u, double s, Eigen::VectorXd& r, double& rnorm, FemStaticReport& rep,
                               std::string& failure) {
  const int32_t inverted = residual(u, s, r);
  if (inverted >= 0) {
    failure = fem_element_text(m_, inverted) + " inverted at load factor " + std::to_string(s);
    return false;
  }
  rnorm = r.norm();
  rep.residual_history.push_back(rnorm);
  return true;
}

bool FemNewton::newton_iterations(std::vector<double>& u, double s, FemStaticReport& rep, std::string& failure) {
  const EigenThreads eigen_threads(o_.threads > 0 ? o_.threads : (k_.nonZeros() > 1000000 ? threads_ : 1));
  projecting_ = o_.projection == FemTangentProjection::always;
  Eigen::VectorXd r, du, r_trial, b;
  double rnorm = 0;
  if (!first_residual(u, s, r, rnorm, rep, failure)) return false;
  const bool linear = m_.every_law(FemLaw::linear);
  const bool in_mm = o_.tolerance_mm > 0;
  std::vector<double> trial(u.size()), gap(u.size());
  bool lifting = held_gap(u, s, gap);
  const auto residual_small = [&](const Eigen::VectorXd& res, double norm) {
    return in_mm ? (res.size() == 0 || res.lpNorm<Eigen::Infinity>() / mean_diagonal_ <= o_.tolerance_mm)
                 : norm <= o_.residual_tolerance * rep.reference_residual;
  };
  if (!lifting && (r.size() == 0 || rnorm <= o_.residual_tolerance * rep.reference_residual)) return true;  // already in equilibrium
  for (int it = 0; it < o_.max_newton_iterations; ++it) {
    auto t0 = Clock::now();
    const int32_t inv = assemble(u, projecting_);
    rep.assembly_seconds += seconds_since(t0);
    if (inv >= 0) {
      failure = fem_element_text(m_, inv) + " inverted at load factor " + std::to_string(s);
      return false;
    }
    // No step is skipped on the millimetre rule's residual alone: a soft (bending) mode's residual is far
    // below mean(diag K) times its error (a cantilever's 1 mN tip load: 1e-7 mm "residual" for a 2 mm
    // deflection), and at a dynamics step's predictor the inertia residual is zero. Only the relative
    // rule accepts the starting point (a warm start that is already the equilibrium).
    b = r;
    if (lifting) lift(gap, b, kbuf_, 1.0, terms_.stiffness_damping != 0 ? &kbuf_n_ : nullptr, terms_.stiffness_damping);
    t0 = Clock::now();
    // Inexact Newton (nonlinear laws): far from equilibrium the step needs no 1e-10 solve; the forcing
    // term follows the residual down, so the last steps are solved as tightly as before.
    const double tolerance = linear || !o_.inexact_newton
                                 ? o_.cg_tolerance
                                 : std::max(o_.cg_tolerance, std::min(kForcingMax, rnorm / std::max(rep.reference_residual, 1e-300)));
    const int cg_it = solve_linear(b, du, tolerance, rep);
    rep.solve_seconds += seconds_since(t0);
    rep.cg_iterations.push_back(cg_it);
    ++rep.newton_iterations;
    if (!du.allFinite()) {
      failure = "the linear solve gave non-finite values at load factor " + std::to_string(s);
      return false;
    }
    // Line search: backtracking until ||r|| or the potential (energy()) decreases, or (lifting) the
    // longest step that inverts nothing. The residual alone rejects good steps of hyperelastic
    // problems: a cantilever's full Newton step leaves a large axial residual from the rotation it
    // makes, and ||r|| crept down in 15 steps of alpha = 1/8 where the energy takes the full step.
    const double slope = lifting ? 0.0 : r.dot(du);  // -dE/dalpha at 0 = r . du on the free components
    // A full step within the budget is taken whatever the residual does (at equilibrium, round-off
    // decides). Without a potential (a discrete gradient: the tangent is approximate), a non-monotone
    // rule: below the largest of the last three residuals (Grippo, Lampariello and Lucidi 1986).
    const double bar = has_potential() ? rnorm : std::max(rnorm, recent_max(rep.residual_history, 3));
    const LineSearch ls = line_search(u, du, gap, lifting, s, bar, slope, linear, in_mm && du.lpNorm<Eigen::Infinity>() <= o_.tolerance_mm,
                                      false, trial, r_trial);
    const double alpha = ls.alpha;
    const bool accepted = ls.accepted;
    const int32_t inverted = ls.inverted;
    if (!accepted) {
      failure = inverted >= 0 ? fem_element_text(m_, inverted) + " inverted in every line-search trial at load factor " + std::to_string(s)
                              : "the line search found no decrease of the residual at load factor " + std::to_string(s);
      return false;
    }
    u.swap(trial);
    r.swap(r_trial);
    rnorm = r.norm();
    rep.residual_history.push_back(rnorm);
    const double step_inf = du.size() ? alpha * du.lpNorm<Eigen::Infinity>() : 0.0;
    lifting = held_gap(u, s, gap);
    if (lifting) continue;
    // Linear (relative rule): K is exact, so one full step solves the system to the linear solve's
    // tolerance (the recursively updated CG residual can sit slightly above residual_tolerance in the
    // true residual; a second step would only repeat the solve).
    if (linear && alpha == 1 && direct_ && factor_current_ && terms_.stiffness_damping == 0) return true;  // exact: K is constant
    if (in_mm) {
      if (alpha == 1 && step_inf <= o_.tolerance_mm && residual_small(r, rnorm)) return true;
    } else if ((linear && alpha == 1) || (residual_small(r, rnorm) && step_inf <= o_.displacement_tolerance * diag_)) {
      return true;
    }
  }
  failure = "Newton did not converge in " + std::to_string(o_.max_newton_iterations) + " iterations at load factor " + std::to_string(s) +
            " (relative residual " + std::to_string(rnorm / std::max(rep.reference_residual, 1e-300)) + ")";
  return false;
}

}  // namespace ctsurg::sim
