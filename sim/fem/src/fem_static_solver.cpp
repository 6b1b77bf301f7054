#include "ctsurg/sim/fem/fem_static_solver.h"

#include "ctsurg/sim/base/parallel.h"
#include "device_conjugate_gradient.h"
#include "fem_cpu_kernels.h"
#include "fem_rigid_modes.h"

#include "ctsurg/core/error.h"

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCore>

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>
#include <string>

namespace ctsurg::sim {
namespace {

constexpr const char* kWhere = "fem static";
constexpr double kForcingMax = 1e-2;  // the inexact Newton forcing term's cap (see newton)
using Clock = std::chrono::steady_clock;
using SpMat = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

void check_node(int32_t id, int32_t n, const char* field) {
  if (id < 0 || id >= n) throw InputError(kWhere, field, "node id " + std::to_string(id) + " out of range [0, " + std::to_string(n) + ")");
}

void validate(const FemModel& model, const FemBoundaryConditions& bc, const FemLoads& loads, const FemStaticOptions& o) {
  const int32_t n = model.node_count();
  for (int32_t i : bc.fixed_nodes) check_node(i, n, "fixed_nodes");
  for (int32_t c : bc.fixed_components)
    if (c < 0 || c >= 3 * n) throw InputError(kWhere, "fixed_components", "component " + std::to_string(c) + " out of range [0, 3 #N)");
  for (int32_t i : bc.prescribed_nodes) check_node(i, n, "prescribed_nodes");
  if (bc.prescribed_displacements.size() != 3 * bc.prescribed_nodes.size())
    throw InputError(kWhere, "prescribed_displacements", "expected #G x 3 = " + std::to_string(3 * bc.prescribed_nodes.size()) + " values");
  for (double d : bc.prescribed_displacements)
    if (!std::isfinite(d)) throw InputError(kWhere, "prescribed_displacements", "must be finite");
  if (!loads.forces.empty() && loads.forces.size() != 3 * static_cast<std::size_t>(n))
    throw InputError(kWhere, "forces", "expected #N x 3 = " + std::to_string(3 * n) + " values or none");
  for (double f : loads.forces)
    if (!std::isfinite(f)) throw InputError(kWhere, "forces", "must be finite");
  for (double g : loads.gravity)
    if (!std::isfinite(g)) throw InputError(kWhere, "gravity", "must be finite");
  if (!(o.residual_tolerance > 0 && o.residual_tolerance < 1)) throw InputError(kWhere, "residual_tolerance", "must be in (0, 1)");
  if (!(o.displacement_tolerance > 0 && o.displacement_tolerance < 1)) throw InputError(kWhere, "displacement_tolerance", "must be in (0, 1)");
  if (!(o.cg_tolerance > 0 && o.cg_tolerance < 1)) throw InputError(kWhere, "cg_tolerance", "must be in (0, 1)");
  if (o.max_newton_iterations < 1) throw InputError(kWhere, "max_newton_iterations", "must be >= 1");
  if (o.load_steps < 1 || o.load_steps > 1 << 20) throw InputError(kWhere, "load_steps", "must be in [1, 2^20]");
  if (o.max_halvings < 0 || o.max_halvings > 30) throw InputError(kWhere, "max_halvings", "must be in [0, 30]");
  if (o.max_line_search < 0 || o.max_line_search > 30) throw InputError(kWhere, "max_line_search", "must be in [0, 30]");
  if (o.cg_max_iterations < 0) throw InputError(kWhere, "cg_max_iterations", "must be >= 0");
  if (o.threads < 0) throw InputError(kWhere, "threads", "must be >= 0");
  if (!o.initial_displacements.empty() && o.initial_displacements.size() != 3 * static_cast<std::size_t>(n))
    throw InputError(kWhere, "initial_displacements", "expected #N x 3 = " + std::to_string(3 * n) + " values or none");
  for (double d : o.initial_displacements)
    if (!std::isfinite(d)) throw InputError(kWhere, "initial_displacements", "must be finite");
}

struct System {
  std::vector<int32_t> free_index;    // #N x 3: index among free components, or -1 if held
  SpMat k;                            // free x free, full (both triangles)
  std::vector<int64_t> contrib_offsets;  // nnz + 1
  std::vector<int64_t> contrib;          // element-matrix entries 144 e + k per non-zero
};

void build_system(const FemModel& model, const std::vector<uint8_t>& held, System& s) {
  const int32_t n = model.node_count(), t = model.tet_count();
  s.free_index.assign(3 * static_cast<std::size_t>(n), -1);
  int32_t free_count = 0;
  for (int32_t d = 0; d < 3 * n; ++d)
    if (!held[d]) s.free_index[d] = free_count++;
  // Pattern: rows of the free components, columns of the free components of the node's neighbours.
  std::vector<std::vector<int32_t>> neighbours(n);
  for (int32_t e = 0; e < t; ++e)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) neighbours[model.tets[4 * e + a]].push_back(model.tets[4 * e + b]);
  std::vector<int> outer(free_count + 1, 0);
  std::vector<int> inner;
  for (int32_t i = 0; i < n; ++i) {
    auto& nb = neighbours[i];
    std::sort(nb.begin(), nb.end());
    nb.erase(std::unique(nb.begin(), nb.end()), nb.end());
    for (int a = 0; a < 3; ++a) {
      const int32_t row = s.free_index[3 * i + a];
      if (row < 0) continue;
      for (int32_t j : nb)
        for (int b = 0; b < 3; ++b)
          if (s.free_index[3 * j + b] >= 0) inner.push_back(s.free_index[3 * j + b]);
      outer[row + 1] = static_cast<int>(inner.size());
    }
  }
  const int64_t nnz = static_cast<int64_t>(inner.size());
  std::vector<double> zeros(nnz, 0.0);
  s.k = Eigen::Map<const SpMat>(free_count, free_count, nnz, outer.data(), inner.data(), zeros.data());
  // Element entry -> non-zero, then grouped per non-zero (counting sort: contributions in element order).
  std::vector<int64_t> slot(144 * static_cast<std::size_t>(t), -1);
  std::vector<int64_t> count(nnz + 1, 0);
  const int* ip = s.k.innerIndexPtr();
  const int* op = s.k.outerIndexPtr();
  for (int32_t e = 0; e < t; ++e)
    for (int r = 0; r < 12; ++r) {
      const int32_t row = s.free_index[3 * model.tets[4 * e + r / 3] + r % 3];
      if (row < 0) continue;
      for (int c = 0; c < 12; ++c) {
        const int32_t col = s.free_index[3 * model.tets[4 * e + c / 3] + c % 3];
        if (col < 0) continue;
        const int* p = std::lower_bound(ip + op[row], ip + op[row + 1], col);
        const int64_t z = p - ip;
        slot[144 * static_cast<std::size_t>(e) + 12 * r + c] = z;
        ++count[z + 1];
      }
    }
  for (int64_t z = 0; z < nnz; ++z) count[z + 1] += count[z];
  s.contrib_offsets = count;
  s.contrib.resize(count[nnz]);
  std::vector<int64_t> fill(count.begin(), count.end() - 1);
  for (std::size_t k = 0; k < slot.size(); ++k)
    if (slot[k] >= 0) s.contrib[fill[slot[k]]++] = static_cast<int64_t>(k);
}

std::string element_text(const FemModel& model, int32_t e) {
  std::ostringstream s;
  s << "element " << e << " (rest centroid";
  for (int c = 0; c < 3; ++c) {
    double x = 0;
    for (int a = 0; a < 4; ++a) x += model.nodes[3 * model.tets[4 * e + a] + c] / 4;
    s << (c ? ", " : " (") << x;
  }
  s << ") mm)";
  return s.str();
}

class Solver {
 public:
  Solver(const FemModel& model, const FemBoundaryConditions& bc, const FemLoads& loads, const FemStaticOptions& o,
         DeviceConjugateGradient* device_cg)
      : m_(model), o_(o), threads_(o.threads > 0 ? o.threads : cpu::thread_count(0, model.tet_count())),
        device_cg_(device_cg) {
    const int32_t n = model.node_count();
    held_.assign(3 * static_cast<std::size_t>(n), 0);
    target_.assign(3 * static_cast<std::size_t>(n), 0.0);
    for (int32_t i : bc.fixed_nodes) held_[3 * i] = held_[3 * i + 1] = held_[3 * i + 2] = 1;
    for (int32_t c : bc.fixed_components) held_[c] = 1;
    for (std::size_t g = 0; g < bc.prescribed_nodes.size(); ++g)
      for (int a = 0; a < 3; ++a) {
        held_[3 * bc.prescribed_nodes[g] + a] = 1;
        target_[3 * bc.prescribed_nodes[g] + a] = bc.prescribed_displacements[3 * g + a];
      }
    diag_ = fem_bounding_diagonal(model);
    check_rigid_modes(model, held_, diag_, kWhere);
    for (int32_t i = 0; i < n; ++i)  // nodes without tets have no stiffness: held where they are
      if (model.node_offsets[i + 1] == model.node_offsets[i]) held_[3 * i] = held_[3 * i + 1] = held_[3 * i + 2] = 1;
    free_count_ = static_cast<Eigen::Index>(std::count(held_.begin(), held_.end(), 0));
    external_.assign(3 * static_cast<std::size_t>(n), 0.0);
    for (int32_t i = 0; i < n; ++i)
      for (int c = 0; c < 3; ++c)
        external_[3 * i + c] = (loads.forces.empty() ? 0.0 : loads.forces[3 * i + c]) + model.node_mass[i] * loads.gravity[c];
    el_ = {model.tets.data(), model.dm_inverse.data(), model.rest_volume.data(), model.tet_count(),
           static_cast<int32_t>(model.material.model), model.lame.mu, model.lame.lambda};
    corner_.resize(12 * static_cast<std::size_t>(model.tet_count()));
    forces_.resize(3 * static_cast<std::size_t>(n));
  }

  FemStaticResult run() {
    const auto t0 = Clock::now();
    FemStaticResult result;
    FemStaticReport& rep = result.report;
    const int32_t n = m_.node_count();
    std::vector<double> u(3 * static_cast<std::size_t>(n), 0.0), trial;
    {  // r_ref: the residual at u = 0 under the full load
      std::vector<double> u_full(u.size(), 0.0);
      apply_held(u_full, 1.0);
      Eigen::VectorXd r;
      residual(u_full, 1.0, r);
      rep.reference_residual = r.norm();
    }
    const int eigen_threads = Eigen::nbThreads();
    build_system(m_, held_, sys_);
    // Eigen's CG runs one OpenMP product per iteration: a thread team per iteration costs more than it
    // saves below ~1e6 non-zeros, and far more when the cores are shared (measured: 10x slower on a
    // loaded 2-core machine). options.threads > 0 forces a count.
    Eigen::setNbThreads(o_.threads > 0 ? o_.threads : (sys_.k.nonZeros() > 1000000 ? threads_ : 1));
    rep.free_components = static_cast<int>(sys_.k.rows());
    kbuf_.resize(144 * static_cast<std::size_t>(m_.tet_count()));

    double factor = 0, increment = 1.0 / o_.load_steps;
    int halvings = 0;
    std::string last_failure;
    if (rep.reference_residual == 0) factor = 1;  // nothing to do: u = 0 is the solution
    if (factor < 1 && !o_.initial_displacements.empty()) {  // warm start: the full load at once
      trial = o_.initial_displacements;  // held components are lifted to their targets by newton()
      if (newton(trial, 1.0, rep, last_failure)) {
        u.swap(trial);
        factor = 1;
        rep.load_factors.push_back(factor);
        ++rep.load_steps;
      } else {
        rep.warm_start_failed = true;
      }
    }
    while (factor < 1) {
      const double next = std::min(1.0, factor + increment);
      trial = u;  // held components at the last factor's values: Newton lifts them (see newton)
      if (newton(trial, next, rep, last_failure)) {
        u.swap(trial);
        factor = next;
        rep.load_factors.push_back(factor);
        ++rep.load_steps;
      } else {
        if (++halvings > o_.max_halvings) {
          Eigen::setNbThreads(eigen_threads);
          std::ostringstream s;
          s << "fem static: the load increment from factor " << factor << " to " << next << " failed after "
            << o_.max_halvings << " halvings (" << last_failure << "); try smaller loads or more load_steps";
          throw RuntimeError(s.str());
        }
        ++rep.halvings;
        increment /= 2;
      }
    }
    Eigen::setNbThreads(eigen_threads);

    Eigen::VectorXd r;
    residual(u, 1.0, r);
    rep.relative_residual = rep.reference_residual > 0 ? r.norm() / rep.reference_residual : 0;
    rep.converged = true;
    result.reactions.assign(u.size(), 0.0);
    for (std::size_t d = 0; d < u.size(); ++d)
      if (held_[d]) result.reactions[d] = -(forces_[d] + external_[d]);
    result.displacements = std::move(u);
    rep.seconds = seconds_since(t0);
    return result;
  }

 private:
  void apply_held(std::vector<double>& u, double s) const {
    for (std::size_t d = 0; d < u.size(); ++d)
      if (held_[d]) u[d] = s * target_[d];
  }

  // r = f_int(u) + s f_ext on the free components (forces_ keeps f_int of all). Returns the lowest
  // inverted element or -1.
  int32_t residual(const std::vector<double>& u, double s, Eigen::VectorXd& r) {
    const int32_t inverted = cpu::fem_forces(el_, m_.node_offsets.data(), m_.node_corners.data(), m_.node_count(),
                                             u.data(), corner_.data(), forces_.data(), threads_);
    r.resize(free_count_);
    Eigen::Index k = 0;
    for (std::size_t d = 0; d < u.size(); ++d)
      if (!held_[d]) r[k++] = forces_[d] + s * external_[d];
    return inverted;
  }

  int32_t assemble(const std::vector<double>& u) {
    const int32_t inverted = cpu::fem_stiffness(el_, u.data(), kbuf_.data(), threads_);
    double* values = sys_.k.valuePtr();
    const int64_t nnz = sys_.k.nonZeros();
    const int64_t* off = sys_.contrib_offsets.data();
    const int64_t* con = sys_.contrib.data();
    const double* kb = kbuf_.data();
#pragma omp parallel for schedule(static) num_threads(threads_)
    for (int64_t z = 0; z < nnz; ++z) {
      double v = 0;
      for (int64_t c = off[z]; c < off[z + 1]; ++c) v += kb[con[c]];
      values[z] = v;
    }
    return inverted;
  }

  template <class Precond>
  int solve_with(Eigen::VectorXd& du, const Eigen::VectorXd& r, double tolerance) {
    Eigen::ConjugateGradient<SpMat, Eigen::Lower | Eigen::Upper, Precond> cg;
    cg.setTolerance(tolerance);
    if (o_.cg_max_iterations > 0) cg.setMaxIterations(o_.cg_max_iterations);
    cg.compute(sys_.k);
    du = cg.solve(r);
    return static_cast<int>(cg.iterations());
  }

  // The same solve on the device (Backend::cuda, Jacobi, Eigen's iteration and stopping rule): the
  // pattern goes up at the first solve (run() builds it once), the values at every solve (one per
  // assembly).
  int solve_on_device(Eigen::VectorXd& du, const Eigen::VectorXd& r, double tolerance) {
    const auto rows = static_cast<int32_t>(sys_.k.rows());
    if (!device_cg_->has_pattern()) device_cg_->set_pattern(rows, sys_.k.outerIndexPtr(), sys_.k.innerIndexPtr());
    device_cg_->set_values(sys_.k.valuePtr());
    du.resize(rows);
    const int64_t max_iterations = o_.cg_max_iterations > 0 ? o_.cg_max_iterations : 2 * static_cast<int64_t>(rows);
    return static_cast<int>(device_cg_->solve(r.data(), du.data(), tolerance, max_iterations).iterations);
  }

  // gap = s target - u on the held components (0 elsewhere); returns whether any is non-zero.
  bool held_gap(const std::vector<double>& u, double s, std::vector<double>& gap) const {
    bool any = false;
    for (std::size_t d = 0; d < u.size(); ++d) {
      gap[d] = held_[d] ? s * target_[d] - u[d] : 0.0;
      any = any || gap[d] != 0;
    }
    return any;
  }

  // b = r - K_fh gap on the free components, K_fh from the element matrices of the last assembly
  // (serial, in element order: deterministic); only elements with a moving held corner contribute.
  void lift(const std::vector<double>& gap, Eigen::VectorXd& b) const {
    const int32_t t = m_.tet_count();
    for (int32_t e = 0; e < t; ++e) {
      const int32_t* v = &m_.tets[4 * e];
      double g[12];
      bool moving = false;
      for (int c = 0; c < 12; ++c) {
        g[c] = gap[3 * v[c / 3] + c % 3];
        moving = moving || g[c] != 0;
      }
      if (!moving) continue;
      const double* k = &kbuf_[144 * static_cast<std::size_t>(e)];
      for (int r = 0; r < 12; ++r) {
        const int32_t row = sys_.free_index[3 * v[r / 3] + r % 3];
        if (row < 0) continue;
        double kg = 0;
        for (int c = 0; c < 12; ++c) kg += k[12 * r + c] * g[c];
        b[row] -= kg;
      }
    }
  }

  // Newton at load factor s from u, whose held components may still sit at an earlier factor's
  // values. While they do (a non-zero gap), an iteration is a lifted (consistent) predictor: the
  // held components move to their targets and the free ones follow through the tangent,
  // K_ff du_f = r_f - K_fh gap, so a grab's displacement spreads over the mesh in one linear step
  // instead of shearing the elements next to the grabbed nodes; it takes the longest step alpha = 1,
  // 1/2, ... that inverts no element (no residual test: the residual at the old held values is not
  // comparable). Then plain Newton iterations with the backtracking line search on ||r||.
  bool newton(std::vector<double>& u, double s, FemStaticReport& rep, std::string& failure) {
    Eigen::VectorXd r, du, r_trial, b;
    const int32_t inv0 = residual(u, s, r);
    if (inv0 >= 0) {
      failure = element_text(m_, inv0) + " inverted at load factor " + std::to_string(s);
      return false;
    }
    double rnorm = r.norm();
    rep.residual_history.push_back(rnorm);
    const bool linear = m_.material.model == FemMaterialModel::linear;
    std::vector<double> trial(u.size()), gap(u.size());
    bool lifting = held_gap(u, s, gap);
    if (!lifting && rnorm <= o_.residual_tolerance * rep.reference_residual) return true;  // already in equilibrium
    for (int it = 0; it < o_.max_newton_iterations; ++it) {
      auto t0 = Clock::now();
      const int32_t inv = assemble(u);
      rep.assembly_seconds += seconds_since(t0);
      if (inv >= 0) {
        failure = element_text(m_, inv) + " inverted at load factor " + std::to_string(s);
        return false;
      }
      b = r;
      if (lifting) lift(gap, b);
      t0 = Clock::now();
      // Inexact Newton (nonlinear laws): far from equilibrium the step needs no 1e-10 solve; the
      // forcing term follows the residual down, so the last steps are solved as tightly as before.
      const double tolerance = linear || !o_.inexact_newton
                                   ? o_.cg_tolerance
                                   : std::max(o_.cg_tolerance, std::min(kForcingMax, rnorm / rep.reference_residual));
      const int cg_it = device_cg_ != nullptr ? solve_on_device(du, b, tolerance)
                        : o_.preconditioner == FemPreconditioner::diagonal
                            ? solve_with<Eigen::DiagonalPreconditioner<double>>(du, b, tolerance)
                            : solve_with<Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::AMDOrdering<int>>>(du, b, tolerance);
      rep.solve_seconds += seconds_since(t0);
      rep.cg_iterations.push_back(cg_it);
      ++rep.newton_iterations;
      if (!du.allFinite()) {
        failure = "the linear solve gave non-finite values at load factor " + std::to_string(s);
        return false;
      }
      // Line search: backtracking on ||r||, or (lifting) the longest step that inverts nothing.
      double alpha = 1;
      bool accepted = false;
      int32_t inverted = -1;
      for (int ls = 0; ls <= o_.max_line_search; ++ls, alpha *= 0.5) {
        trial = u;
        Eigen::Index k = 0;
        for (std::size_t d = 0; d < u.size(); ++d) {
          if (!held_[d]) trial[d] += alpha * du[k++];
          else if (lifting) trial[d] = alpha == 1 ? s * target_[d] : u[d] + alpha * gap[d];  // exact at alpha = 1
        }
        inverted = residual(trial, s, r_trial);
        if (inverted >= 0) continue;
        if (lifting || r_trial.norm() < rnorm || linear) {
          accepted = true;
          break;
        }
      }
      if (!accepted) {
        failure = inverted >= 0 ? element_text(m_, inverted) + " inverted in every line-search trial at load factor " + std::to_string(s)
                                : "the line search found no decrease of the residual at load factor " + std::to_string(s);
        return false;
      }
      u.swap(trial);
      r.swap(r_trial);
      rnorm = r.norm();
      rep.residual_history.push_back(rnorm);
      const double step_inf = alpha * du.lpNorm<Eigen::Infinity>();
      const bool small_residual = rnorm <= o_.residual_tolerance * rep.reference_residual;
      lifting = held_gap(u, s, gap);
      if (lifting) continue;
      // Linear: K is exact, so one full step solves the system to the CG tolerance (the recursively
      // updated CG residual can sit slightly above residual_tolerance in the true residual; a second
      // step would only repeat the solve).
      if ((linear && alpha == 1) || (small_residual && step_inf <= o_.displacement_tolerance * diag_)) return true;
    }
    failure = "Newton did not converge in " + std::to_string(o_.max_newton_iterations) + " iterations at load factor " +
              std::to_string(s) + " (relative residual " + std::to_string(rnorm / rep.reference_residual) + ")";
    return false;
  }

  const FemModel& m_;
  FemStaticOptions o_;
  int threads_;
  double diag_ = 1;
  Eigen::Index free_count_ = 0;
  std::vector<uint8_t> held_;
  std::vector<double> target_, external_, corner_, forces_, kbuf_;
  FemElementView<double> el_{};
  System sys_;
  DeviceConjugateGradient* device_cg_;  // Backend::cuda: the linear solves on the device; null for cpu
};

}  // namespace

FemStaticResult solve_fem_static(const FemModel& model, const FemBoundaryConditions& bc, const FemLoads& loads,
                                 const FemStaticOptions& options, Backend backend) {
  if (!backend_available(backend)) require_backend(backend, kWhere);  // cuda without a CUDA build or device: says why
  std::unique_ptr<DeviceConjugateGradient> device_cg;
  if (backend == Backend::cuda) {
    if (options.preconditioner != FemPreconditioner::diagonal)
      throw InputError(kWhere, "preconditioner",
                       "the cuda backend's conjugate gradient is diagonal (Jacobi) preconditioned; use diagonal, or "
                       "incomplete_cholesky on the cpu backend");
    device_cg = std::make_unique<DeviceConjugateGradient>(kWhere);
  }
  validate(model, bc, loads, options);
  Solver solver(model, bc, loads, options, device_cg.get());
  return solver.run();
}

}  // namespace ctsurg::sim
