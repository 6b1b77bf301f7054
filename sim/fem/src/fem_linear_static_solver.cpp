#include "ctsurg/sim/fem/fem_linear_static_solver.h"

#include "ctsurg/sim/base/parallel.h"
#include "fem_cpu_kernels.h"
#include "fem_element_view.h"
#include "fem_rigid_modes.h"
#include "sparse_cholesky.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/elapsed_seconds.h"

#include <Eigen/Cholesky>
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCore>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <string>

namespace ctsurg::sim {
namespace {

constexpr const char* kLinearSolverWhere = "fem linear solver";
using Clock = std::chrono::steady_clock;
using SpMat = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

}  // namespace

struct FemLinearStaticSolver::Impl {
  const FemModel& model;
  FemLinearSolverOptions options;
  int threads = 1;
  FemLinearSolverStats stats;
  std::vector<uint8_t> supported;           // #N x 3: held by a support (or the node is unused)
  std::vector<int32_t> free_index;          // #N x 3: index in s, or -1
  std::vector<int32_t> support_rows;        // components (3 node + axis) of supported used nodes
  SpMat k;                                  // s x s, both triangles
  Eigen::SparseMatrix<double, Eigen::RowMajor, int> k_support;  // support_rows x s (reactions)
  SparseCholesky cholesky{kLinearSolverWhere};           // K_ss (CHOLMOD, sparse_cholesky.h)
  std::vector<std::array<int32_t, 3>> node_columns;  // #N: column slot per axis, -1 = none (yet)
  std::vector<uint8_t> has_columns;                  // #N
  std::vector<Eigen::VectorXd> columns;              // K_ss^-1 e_j per slot
  std::array<double, 3> gravity_cached{0, 0, 0};
  Eigen::VectorXd gravity_column;                    // K_ss^-1 M g for gravity_cached (empty: none)
  std::vector<int32_t> grab_cached;                  // the node set whose C_pp factor is kept
  Eigen::LLT<Eigen::MatrixXd> grab_factor;
  // Grabs of more than max_grab_nodes nodes: K_ff factorised for the node set direct_cached.
  std::vector<int32_t> direct_cached;
  std::unique_ptr<SparseCholesky> direct_factor;
  std::vector<int32_t> direct_index;                 // s: index in f, or -1 (on p)

  Impl(const FemModel& m, const FemBoundaryConditions& supports, const FemLinearSolverOptions& o)
      : model(m), options(o), threads(o.threads > 0 ? o.threads : cpu::thread_count(0, m.tet_count())) {
    const auto t0 = Clock::now();
    const int32_t n = m.node_count();
    if (m.order != 1)
      throw InputError(kLinearSolverWhere, "order", "the condensed solver is for linear tets; quadratic ones solve with solve_fem_static");
    if (!m.every_law(FemLaw::linear))
      throw InputError(kLinearSolverWhere, "material", "the factorised solver is for the linear material only (its K is constant); use solve_fem_static for St. Venant-Kirchhoff or Neo-Hookean");
    if (!supports.prescribed_nodes.empty() || !supports.prescribed_displacements.empty())
      throw InputError(kLinearSolverWhere, "prescribed_nodes", "supports are fixed nodes and components only; pass grabs to solve()");
    if (!(o.residual_tolerance > 0 && o.residual_tolerance < 1)) throw InputError(kLinearSolverWhere, "residual_tolerance", "must be in (0, 1)");
    if (o.max_refinements < 0 || o.max_refinements > 10) throw InputError(kLinearSolverWhere, "max_refinements", "must be in [0, 10]");
    if (o.max_force_nodes < 0) throw InputError(kLinearSolverWhere, "max_force_nodes", "must be >= 0");
    if (o.max_grab_nodes < 0) throw InputError(kLinearSolverWhere, "max_grab_nodes", "must be >= 0");
    if (o.threads < 0) throw InputError(kLinearSolverWhere, "threads", "must be >= 0");
    supported.assign(3 * static_cast<std::size_t>(n), 0);
    for (int32_t i : supports.fixed_nodes) {
      if (i < 0 || i >= n) throw InputError(kLinearSolverWhere, "fixed_nodes", "node id " + std::to_string(i) + " out of range [0, " + std::to_string(n) + ")");
      supported[3 * i] = supported[3 * i + 1] = supported[3 * i + 2] = 1;
    }
    for (int32_t c : supports.fixed_components) {
      if (c < 0 || c >= 3 * n) throw InputError(kLinearSolverWhere, "fixed_components", "component " + std::to_string(c) + " out of range [0, 3 #N)");
      supported[c] = 1;
    }
    check_rigid_modes(m, supported, fem_bounding_diagonal(m), kLinearSolverWhere);
    free_index.assign(supported.size(), -1);
    int32_t s = 0;
    for (int32_t i = 0; i < n; ++i) {
      const bool used = m.node_offsets[i + 1] > m.node_offsets[i];
      for (int a = 0; a < 3; ++a) {
        if (!used) supported[3 * i + a] = 1;  // no stiffness: held where it is
        if (!supported[3 * i + a]) free_index[3 * i + a] = s++;
        else if (used) support_rows.push_back(3 * i + a);
      }
    }
    // K at u = 0 (the linear material's tangent is its stiffness) from the element matrices.
    std::vector<double> kbuf(144 * static_cast<std::size_t>(m.tet_count()));
    const std::vector<double> zero(3 * static_cast<std::size_t>(n), 0.0);
    const FemElementView<double> el = fem_element_view(m);
    cpu::fem_stiffness(el, zero.data(), kbuf.data(), threads);
    std::vector<int32_t> support_row_of(supported.size(), -1);
    for (std::size_t r = 0; r < support_rows.size(); ++r) support_row_of[support_rows[r]] = static_cast<int32_t>(r);
    std::vector<Eigen::Triplet<double, int>> kt, rt;
    kt.reserve(144 * static_cast<std::size_t>(m.tet_count()));
    for (int32_t e = 0; e < m.tet_count(); ++e)
      for (int r = 0; r < 12; ++r) {
        const int32_t gr = 3 * m.tets[4 * e + r / 3] + r % 3;
        for (int c = 0; c < 12; ++c) {
          const int32_t col = free_index[3 * m.tets[4 * e + c / 3] + c % 3];
          if (col < 0) continue;
          const double v = kbuf[144 * static_cast<std::size_t>(e) + 12 * r + c];
          if (free_index[gr] >= 0) kt.emplace_back(free_index[gr], col, v);
          else if (support_row_of[gr] >= 0) rt.emplace_back(support_row_of[gr], col, v);
        }
      }
    k.resize(s, s);
    k.setFromTriplets(kt.begin(), kt.end());
    k_support.resize(static_cast<Eigen::Index>(support_rows.size()), s);
    k_support.setFromTriplets(rt.begin(), rt.end());
    k.makeCompressed();
    cholesky.analyze(s, k.outerIndexPtr(), k.innerIndexPtr());
    if (cholesky.factorize(k.valuePtr()) >= 0)
      throw InputError(kLinearSolverWhere, "boundary conditions",
                       "the stiffness matrix is not positive definite under these supports (a part of the mesh is not "
                       "connected to any fixed node?); fix nodes on every connected part");
    node_columns.assign(n, {-1, -1, -1});
    has_columns.assign(n, 0);
    stats.free_components = s;
    stats.factor_nonzeros = cholesky.factor_nonzeros();
    stats.factor_seconds = seconds_since(t0);
  }

  // Columns K_ss^-1 e_j for every free component of `nodes` that has none yet, in parallel (each
  // column is computed alone: the same bits for any thread count).
  void ensure_columns(const std::vector<int32_t>& nodes) {
    std::vector<std::pair<int32_t, int32_t>> todo;  // (slot, free index)
    for (int32_t i : nodes) {
      if (has_columns[i]) continue;
      has_columns[i] = 1;
      for (int a = 0; a < 3; ++a) {
        const int32_t j = free_index[3 * i + a];
        if (j < 0) continue;
        node_columns[i][a] = static_cast<int32_t>(columns.size() + todo.size());
        todo.emplace_back(node_columns[i][a], j);
      }
    }
    if (todo.empty()) return;
    const auto t0 = Clock::now();
    columns.resize(columns.size() + todo.size());
    const int64_t count = static_cast<int64_t>(todo.size());
    // All the new columns in one multi-right-hand-side solve (BLAS 3 over the supernodes).
    Eigen::MatrixXd e = Eigen::MatrixXd::Zero(k.rows(), count);
    for (int64_t t = 0; t < count; ++t) e(todo[t].second, t) = 1;
    cholesky.solve(e.data(), e.data(), static_cast<int32_t>(count));
    for (int64_t t = 0; t < count; ++t) columns[todo[t].first] = e.col(t);
    stats.columns += count;
    stats.column_seconds += seconds_since(t0);
  }

  // K_ff = K_ss without the rows and columns p (the grabbed free components of `gnodes`), analysed and
  // factorised into direct_factor; direct_index maps s to f.
  void factor_without(const std::vector<int32_t>& p, const std::vector<int32_t>& gnodes) {
    const auto t0 = Clock::now();
    const Eigen::Index s = k.rows();
    direct_index.assign(static_cast<std::size_t>(s), 0);
    for (int32_t j : p) direct_index[j] = -1;
    int32_t nf = 0;
    for (Eigen::Index i = 0; i < s; ++i)
      if (direct_index[i] >= 0) direct_index[i] = nf++;
    std::vector<Eigen::Triplet<double, int>> t;
    t.reserve(static_cast<std::size_t>(k.nonZeros()));
    for (Eigen::Index c = 0; c < k.outerSize(); ++c) {
      if (direct_index[c] < 0) continue;
      for (SpMat::InnerIterator it(k, c); it; ++it)
        if (direct_index[it.row()] >= 0) t.emplace_back(direct_index[it.row()], direct_index[c], it.value());
    }
    SpMat kff(nf, nf);
    kff.setFromTriplets(t.begin(), t.end());
    kff.makeCompressed();
    direct_factor = std::make_unique<SparseCholesky>(kLinearSolverWhere);
    direct_factor->analyze(nf, kff.outerIndexPtr(), kff.innerIndexPtr());
    if (direct_factor->factorize(kff.valuePtr()) >= 0)
      throw InputError(kLinearSolverWhere, "prescribed_nodes", "the stiffness without the grabbed components is not positive definite");
    direct_cached = gnodes;
    stats.column_seconds += seconds_since(t0);
  }

  // u = K_ss^-1 b + C_:p lambda with (u)_p = target (p: free indices, slots: their columns).
  void constrain(Eigen::VectorXd& u, const std::vector<int32_t>& p, const std::vector<int32_t>& slots, const Eigen::VectorXd& target) {
    if (p.empty()) return;
    Eigen::VectorXd rhs(static_cast<Eigen::Index>(p.size()));
    for (std::size_t i = 0; i < p.size(); ++i) rhs[static_cast<Eigen::Index>(i)] = target[static_cast<Eigen::Index>(i)] - u[p[i]];
    const Eigen::VectorXd lambda = grab_factor.solve(rhs);
    for (std::size_t j = 0; j < p.size(); ++j) u += lambda[static_cast<Eigen::Index>(j)] * columns[slots[j]];
  }

  FemStaticResult solve(const std::vector<int32_t>& gnodes, const std::vector<double>& gdisp, const FemLoads& loads) {
    const auto t0 = Clock::now();
    const double columns_before = stats.column_seconds;
    const int32_t n = model.node_count();
    const std::size_t n3 = 3 * static_cast<std::size_t>(n);
    // Checks first: nothing is computed for a bad call.
    if (gdisp.size() != 3 * gnodes.size())
      throw InputError(kLinearSolverWhere, "prescribed_displacements", "expected #G x 3 = " + std::to_string(3 * gnodes.size()) + " values");
    for (double d : gdisp)
      if (!std::isfinite(d)) throw InputError(kLinearSolverWhere, "prescribed_displacements", "must be finite");
    std::vector<uint8_t> grabbed(n, 0);
    for (int32_t i : gnodes) {
      if (i < 0 || i >= n) throw InputError(kLinearSolverWhere, "prescribed_nodes", "node id " + std::to_string(i) + " out of range [0, " + std::to_string(n) + ")");
      if (grabbed[i]) throw InputError(kLinearSolverWhere, "prescribed_nodes", "node " + std::to_string(i) + " is listed twice");
      const bool used = model.node_offsets[i + 1] > model.node_offsets[i];
      // A node held in some axes is grabbed in the others (its held components are not in p below).
      if (used && supported[3 * i] && supported[3 * i + 1] && supported[3 * i + 2])
        throw InputError(kLinearSolverWhere, "prescribed_nodes", "node " + std::to_string(i) + " is held by a support in every axis; a grab cannot move it");
      grabbed[i] = 1;
    }
    if (!loads.forces.empty() && loads.forces.size() != n3)
      throw InputError(kLinearSolverWhere, "forces", "expected #N x 3 = " + std::to_string(n3) + " values or none");
    for (double f : loads.forces)
      if (!std::isfinite(f)) throw InputError(kLinearSolverWhere, "forces", "must be finite");
    for (double g : loads.gravity)
      if (!std::isfinite(g)) throw InputError(kLinearSolverWhere, "gravity", "must be finite");

    const Eigen::Index s = k.rows();
    // External forces on every component (reactions need the supported ones too) and on s.
    std::vector<double> fext(n3, 0.0);
    const bool has_gravity = loads.gravity[0] != 0 || loads.gravity[1] != 0 || loads.gravity[2] != 0;
    std::vector<int32_t> loaded;  // nodes with a force on a free component
    for (int32_t i = 0; i < n; ++i) {
      bool any = false;
      for (int a = 0; a < 3; ++a) {
        const double f = loads.forces.empty() ? 0.0 : loads.forces[3 * i + a];
        fext[3 * i + a] = f + model.node_mass[i] * loads.gravity[a];
        any = any || (f != 0 && free_index[3 * i + a] >= 0);
      }
      if (any) loaded.push_back(i);
    }
    Eigen::VectorXd f = Eigen::VectorXd::Zero(s);
    for (std::size_t d = 0; d < n3; ++d)
      if (free_index[d] >= 0) f[free_index[d]] = fext[d];

    // A large grab: K_ff factorised per node set (see the header), no columns.
    const bool direct = static_cast<int>(gnodes.size()) > options.max_grab_nodes;
    // u_0 = K_ss^-1 f: columns of the loaded nodes plus gravity's, or one back-substitution.
    Eigen::VectorXd u = Eigen::VectorXd::Zero(s);
    if (direct) {
      // u comes from the K_ff solve below.
    } else if (static_cast<int>(loaded.size()) <= options.max_force_nodes) {
      ensure_columns(loaded);
      for (int32_t i : loaded)
        for (int a = 0; a < 3; ++a)
          if (node_columns[i][a] >= 0 && loads.forces[3 * i + a] != 0) u += loads.forces[3 * i + a] * columns[node_columns[i][a]];
      if (has_gravity) {
        if (gravity_column.size() == 0 || gravity_cached != loads.gravity) {
          Eigen::VectorXd mg = Eigen::VectorXd::Zero(s);
          for (int32_t i = 0; i < n; ++i)
            for (int a = 0; a < 3; ++a)
              if (free_index[3 * i + a] >= 0) mg[free_index[3 * i + a]] = model.node_mass[i] * loads.gravity[a];
          gravity_column.resize(s);
          cholesky.solve(mg.data(), gravity_column.data());
          gravity_cached = loads.gravity;
        }
        u += gravity_column;
      }
    } else {
      cholesky.solve(f.data(), u.data());
    }

    // The grab: prescribed free components p, their targets, and C_pp's factor (kept per node set).
    std::vector<int32_t> p, slots;
    Eigen::VectorXd target(static_cast<Eigen::Index>(3 * gnodes.size()));
    if (!direct) ensure_columns(gnodes);
    for (std::size_t g = 0; g < gnodes.size(); ++g)
      for (int a = 0; a < 3; ++a) {
        const int32_t j = free_index[3 * gnodes[g] + a];
        if (j < 0) continue;
        target[static_cast<Eigen::Index>(p.size())] = gdisp[3 * g + a];
        p.push_back(j);
        if (!direct) slots.push_back(node_columns[gnodes[g]][a]);
      }
    target.conservativeResize(static_cast<Eigen::Index>(p.size()));
    if (direct && gnodes != direct_cached) factor_without(p, gnodes);
    // du = the correction for a residual rf on s (zero on p): with the columns, K_ss^-1 rf then the
    // constraint; directly, K_ff^-1 rf_f.
    const auto correction = [&](const Eigen::VectorXd& rf, const Eigen::VectorXd& on_p) {
      Eigen::VectorXd du = Eigen::VectorXd::Zero(s);
      if (direct) {
        Eigen::VectorXd bf(direct_factor->size());
        for (Eigen::Index i = 0; i < s; ++i)
          if (direct_index[i] >= 0) bf[direct_index[i]] = rf[i];
        direct_factor->solve(bf.data(), bf.data());
        for (Eigen::Index i = 0; i < s; ++i)
          if (direct_index[i] >= 0) du[i] = bf[direct_index[i]];
        for (std::size_t i = 0; i < p.size(); ++i) du[p[i]] = on_p[static_cast<Eigen::Index>(i)];
      } else {
        cholesky.solve(rf.data(), du.data());
        constrain(du, p, slots, on_p);
      }
      return du;
    };
    if (direct) {
      // u = d on p; u_f = K_ff^-1 (f_f - K_fp d).
      Eigen::VectorXd d = Eigen::VectorXd::Zero(s);
      for (std::size_t i = 0; i < p.size(); ++i) d[p[i]] = target[static_cast<Eigen::Index>(i)];
      const Eigen::VectorXd rhs = f - k * d;
      u = correction(rhs, target);
    }
    if (!direct && !p.empty() && gnodes != grab_cached) {
      const Eigen::Index m = static_cast<Eigen::Index>(p.size());
      Eigen::MatrixXd c(m, m);
      for (Eigen::Index j = 0; j < m; ++j)
        for (Eigen::Index i = 0; i < m; ++i) c(i, j) = columns[slots[j]][p[i]];
      grab_factor.compute(0.5 * (c + c.transpose()));  // K^-1 is symmetric; C_pp is a principal block
      grab_cached = gnodes;
      if (grab_factor.info() != Eigen::Success)
        throw InputError(kLinearSolverWhere, "prescribed_nodes", "the grabbed nodes' compliance matrix is singular (repeated or coincident nodes?)");
    }
    if (!direct) constrain(u, p, slots, target);

    // Self-check: the true residual on f = s \ p, against the residual of "d on p, 0 elsewhere".
    std::vector<uint8_t> on_p(static_cast<std::size_t>(s), 0);
    for (int32_t j : p) on_p[j] = 1;
    Eigen::MatrixXd uu(s, 2);
    uu.col(0) = u;
    uu.col(1).setZero();
    for (std::size_t i = 0; i < p.size(); ++i) uu(p[i], 0) = uu(p[i], 1) = target[static_cast<Eigen::Index>(i)];
    auto free_norm = [&](const Eigen::VectorXd& r) {
      double q = 0;
      for (Eigen::Index i = 0; i < s; ++i)
        if (!on_p[i]) q += r[i] * r[i];
      return std::sqrt(q);
    };
    Eigen::MatrixXd ku = k * uu;
    Eigen::VectorXd r = ku.col(0) - f;
    FemStaticResult result;
    FemStaticReport& rep = result.report;
    rep.reference_residual = free_norm(ku.col(1) - f);
    rep.residual_history.push_back(rep.reference_residual);
    double rnorm = free_norm(r);
    rep.residual_history.push_back(rnorm);
    rep.newton_iterations = 1;
    const double goal = options.residual_tolerance * rep.reference_residual;
    for (int it = 0; it < options.max_refinements && rnorm > goal; ++it) {  // one refinement: u += K_ff^-1 (-r_f)
      Eigen::VectorXd rf = -r;
      for (int32_t j : p) rf[j] = 0;
      uu.col(0) += correction(rf, Eigen::VectorXd::Zero(static_cast<Eigen::Index>(p.size())));
      for (std::size_t i = 0; i < p.size(); ++i) uu(p[i], 0) = target[static_cast<Eigen::Index>(i)];
      r = k * uu.col(0) - f;
      rnorm = free_norm(r);
      rep.residual_history.push_back(rnorm);
      ++rep.newton_iterations;
    }
    rep.relative_residual = rep.reference_residual > 0 ? rnorm / rep.reference_residual : 0;
    rep.converged = rnorm <= goal || rep.reference_residual == 0;
    rep.load_steps = 1;
    rep.load_factors = {1.0};
    rep.free_components = static_cast<int>(s - static_cast<Eigen::Index>(p.size()));

    // Displacements (#N x 3) and reactions -(f_int + f_ext) = K u - f_ext on held components.
    result.displacements.assign(n3, 0.0);
    result.reactions.assign(n3, 0.0);
    for (std::size_t d = 0; d < n3; ++d)
      if (free_index[d] >= 0) result.displacements[d] = uu(free_index[d], 0);
    for (std::size_t g = 0; g < gnodes.size(); ++g)  // exact targets (also for unused nodes)
      for (int a = 0; a < 3; ++a) result.displacements[3 * gnodes[g] + a] = gdisp[3 * g + a];
    for (std::size_t g = 0; g < gnodes.size(); ++g)
      for (int a = 0; a < 3; ++a) {
        const int32_t j = free_index[3 * gnodes[g] + a];
        if (j >= 0) result.reactions[3 * gnodes[g] + a] = r[j];
      }
    const Eigen::VectorXd ks = k_support * uu.col(0);
    for (std::size_t q = 0; q < support_rows.size(); ++q)
      result.reactions[support_rows[q]] = ks[static_cast<Eigen::Index>(q)] - fext[support_rows[q]];
    rep.solve_seconds = stats.column_seconds - columns_before;
    rep.seconds = seconds_since(t0);
    return result;
  }
};

FemLinearStaticSolver::FemLinearStaticSolver(const FemModel& model, const FemBoundaryConditions& supports,
                                             const FemLinearSolverOptions& options)
    : impl_(std::make_unique<Impl>(model, supports, options)) {}

FemLinearStaticSolver::~FemLinearStaticSolver() = default;

FemStaticResult FemLinearStaticSolver::solve(const std::vector<int32_t>& prescribed_nodes,
                                             const std::vector<double>& prescribed_displacements, const FemLoads& loads) {
  return impl_->solve(prescribed_nodes, prescribed_displacements, loads);
}

const FemLinearSolverStats& FemLinearStaticSolver::stats() const { return impl_->stats; }

}  // namespace ctsurg::sim
