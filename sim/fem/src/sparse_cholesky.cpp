#include "sparse_cholesky.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/memory_guard.h"
#include "ctsurg/core/elapsed_seconds.h"

#include <cholmod.h>
#include <dlfcn.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstring>
#include <vector>

// The BLAS's single-precision matrix-vector product and double-precision triangular solve with many
// right-hand sides (Fortran interface: every BLAS has them; the same library CHOLMOD's double-precision
// substitutions run on).
extern "C" {
void sgemv_(const char* trans, const int* m, const int* n, const float* alpha, const float* a, const int* lda, const float* x,
            const int* incx, const float* beta, float* y, const int* incy);
void dtrsm_(const char* side, const char* uplo, const char* transa, const char* diag, const int* m, const int* n,
            const double* alpha, const double* a, const int* lda, double* b, const int* ldb);
}

namespace ctsurg::sim {

// The single-precision substitutions run on this many disjoint subtrees of the supernodal elimination
// tree at once, then on the supernodes above them (the top) in order. Fixed, not the thread count: the
// groups' updates of the top's rows are summed in group order, so the bits are the same on any machine
// (one thread runs the groups one after the other).
constexpr int kSubstitutionGroups = 2;

struct SubstitutionSchedule {
  std::vector<int32_t> groups[kSubstitutionGroups];  // each group's supernodes, ascending (children first)
  std::vector<int32_t> top;                          // the other supernodes, ascending
  std::vector<int32_t> top_rows;                     // the top's columns (rows the groups update)
  std::vector<int8_t> owner;                         // per column: its supernode's group, or -1 (the top)
  size_t max_rows = 0;                               // the most rows of a supernode (the steps' scratch)
};

namespace {

using Clock = std::chrono::steady_clock;

// The BLAS's own thread count, when it has one (OpenBLAS: openblas_set_num_threads, looked up at run
// time so that any BLAS links), set to one: (1) the results must not depend on the machine's core count
// (OpenBLAS blocks its products differently for 2 threads: other last bits, so another machine would
// write other trajectories); (2) the supernodal solves are many small matrix-vector products, and with
// OpenBLAS's threads each waits for a second core, which on a loaded machine yields for a whole time
// slice (measured: a heart solve went from 4 ms to seconds). Parallelism stays where it is
// deterministic: OpenMP over elements and nodes.
void set_blas_threads(int threads) {
  using SetThreads = void (*)(int);
  static const SetThreads set = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
  if (set != nullptr) set(threads);
}

// Splits the supernodal elimination tree (parent: the supernode of each supernode's first row below its
// own columns; none for a root) into kSubstitutionGroups sets of whole subtrees of about equal work
// (a supernode's work: its block's entries) and the top: the heaviest subtree of the candidates is
// replaced by its children (it joins the top) until the candidates pack into the groups within 5 % of
// each other, or the top holds a quarter of the work (then the split stays as it is).
SubstitutionSchedule substitution_schedule(const cholmod_factor& f) {
  const auto nsuper = static_cast<int32_t>(f.nsuper);
  const auto* super = static_cast<const int32_t*>(f.super);
  const auto* pi = static_cast<const int32_t*>(f.pi);
  const auto* rows = static_cast<const int32_t*>(f.s);
  std::vector<int32_t> super_of(f.n);
  for (int32_t k = 0; k < nsuper; ++k)
    for (int32_t c = super[k]; c < super[k + 1]; ++c) super_of[static_cast<size_t>(c)] = k;
  std::vector<int32_t> parent(static_cast<size_t>(nsuper), -1);
  std::vector<int64_t> work(static_cast<size_t>(nsuper));  // the subtree's entries
  std::vector<std::vector<int32_t>> children(static_cast<size_t>(nsuper));
  std::vector<int32_t> candidates;
  int64_t total = 0;
  for (int32_t k = 0; k < nsuper; ++k) {  // children before parents (k < parent)
    const int32_t ncols = super[k + 1] - super[k], nrows = pi[k + 1] - pi[k];
    work[static_cast<size_t>(k)] += static_cast<int64_t>(ncols) * nrows;
    total += static_cast<int64_t>(ncols) * nrows;
    if (nrows > ncols) {
      const int32_t p = super_of[static_cast<size_t>(rows[pi[k] + ncols])];
      parent[static_cast<size_t>(k)] = p;
      work[static_cast<size_t>(p)] += work[static_cast<size_t>(k)];
      children[static_cast<size_t>(p)].push_back(k);
    } else {
      candidates.push_back(k);
    }
  }
  std::vector<uint8_t> in_top(static_cast<size_t>(nsuper), 0);
  int64_t top_work = 0;
  std::vector<int32_t> assignment;  // per candidate: its group
  for (;;) {
    // Greedy packing, heaviest first (ties by supernode): each to the lightest group.
    std::vector<int32_t> order = candidates;
    std::sort(order.begin(), order.end(), [&](int32_t a, int32_t b) {
      return work[static_cast<size_t>(a)] != work[static_cast<size_t>(b)] ? work[static_cast<size_t>(a)] > work[static_cast<size_t>(b)] : a < b;
    });
    std::array<int64_t, kSubstitutionGroups> load{};
    assignment.assign(order.size(), 0);
    for (size_t i = 0; i < order.size(); ++i) {
      const auto g = static_cast<int32_t>(std::min_element(load.begin(), load.end()) - load.begin());
      assignment[i] = g;
      load[static_cast<size_t>(g)] += work[static_cast<size_t>(order[i])];
    }
    candidates = order;
    const int64_t most = *std::max_element(load.begin(), load.end()), least = *std::min_element(load.begin(), load.end());
    if (order.empty() || most - least <= most / 20 || 4 * top_work >= total) break;
    const int32_t heaviest = order.front();
    const int32_t own = super[heaviest + 1] - super[heaviest];
    if (children[static_cast<size_t>(heaviest)].empty()) break;  // a leaf: nothing to split
    in_top[static_cast<size_t>(heaviest)] = 1;
    top_work += static_cast<int64_t>(own) * (pi[heaviest + 1] - pi[heaviest]);
    candidates.erase(candidates.begin());
    for (int32_t c : children[static_cast<size_t>(heaviest)]) candidates.push_back(c);
  }
  SubstitutionSchedule out;
  std::vector<int8_t> group_of(static_cast<size_t>(nsuper), -1);
  for (size_t i = 0; i < candidates.size(); ++i) group_of[static_cast<size_t>(candidates[i])] = static_cast<int8_t>(assignment[i]);
  for (int32_t k = nsuper - 1; k >= 0; --k)  // parents before children: a subtree inherits its root's group
    if (group_of[static_cast<size_t>(k)] < 0 && !in_top[static_cast<size_t>(k)] && parent[static_cast<size_t>(k)] >= 0)
      group_of[static_cast<size_t>(k)] = group_of[static_cast<size_t>(parent[static_cast<size_t>(k)])];
  out.owner.assign(f.n, -1);
  for (int32_t k = 0; k < nsuper; ++k) {
    out.max_rows = std::max(out.max_rows, static_cast<size_t>(pi[k + 1] - pi[k]));
    const int8_t g = in_top[static_cast<size_t>(k)] ? int8_t{-1} : group_of[static_cast<size_t>(k)];
    if (g < 0) {
      out.top.push_back(k);
      for (int32_t c = super[k]; c < super[k + 1]; ++c) out.top_rows.push_back(c);
    } else {
      out.groups[g].push_back(k);
    }
    for (int32_t c = super[k]; c < super[k + 1]; ++c) out.owner[static_cast<size_t>(c)] = g;
  }
  return out;
}

}  // namespace

struct SparseCholesky::Impl {
  std::string where;
  cholmod_common common{};
  cholmod_factor* factor = nullptr;
  // The pattern, kept for the values' view (CHOLMOD reads the matrix through a cholmod_sparse that
  // points into these arrays: no copy).
  std::vector<int32_t> outer, inner;
  int32_t n = 0;
  bool numeric = false;
  std::vector<float> single;       // make_single(): the blocks W_k = [L_kk; L_bk] L_kk^-1 in float (empty: none)
  SubstitutionSchedule schedule;   // make_single(): the supernodes in kSubstitutionGroups subtrees and the top
  mutable std::vector<float> work;
  mutable std::vector<float> group_buffers[kSubstitutionGroups];  // per group: its products, its updates of the top's rows
  double analyze_s = 0, factor_s = 0;

  explicit Impl(std::string w) : where(std::move(w)) {
    cholmod_start(&common);
    common.print = 0;               // no messages of its own: its status becomes ours
    common.error_handler = nullptr;
    common.supernodal = CHOLMOD_SUPERNODAL;
    common.final_ll = 1;            // keep L L^T (the supernodal factor is LL^T anyway)
  }
  ~Impl() {
    if (factor != nullptr) cholmod_free_factor(&factor, &common);
    cholmod_finish(&common);
  }

  cholmod_sparse view(const double* values) {
    cholmod_sparse a{};
    a.nrow = a.ncol = static_cast<size_t>(n);
    a.nzmax = inner.size();
    a.p = outer.data();
    a.i = inner.data();
    a.x = const_cast<double*>(values);
    a.stype = -1;  // symmetric, lower triangle used (of CSC; the matrix is its own transpose)
    a.itype = CHOLMOD_INT;
    a.xtype = values != nullptr ? CHOLMOD_REAL : CHOLMOD_PATTERN;
    a.dtype = CHOLMOD_DOUBLE;
    a.sorted = 1;
    a.packed = 1;
    return a;
  }

  [[noreturn]] void fail(const std::string& what) const {
    std::string why;
    switch (common.status) {
      case CHOLMOD_OUT_OF_MEMORY: why = "out of memory"; break;
      case CHOLMOD_TOO_LARGE: why = "the problem is too large for 32-bit indices"; break;
      case CHOLMOD_INVALID: why = "invalid input"; break;
      default: why = "CHOLMOD status " + std::to_string(common.status);
    }
    throw RuntimeError(where + ": " + what + " of " + std::to_string(n) + " unknowns failed: " + why);
  }
};

SparseCholesky::SparseCholesky(std::string where) : impl_(std::make_unique<Impl>(std::move(where))) { set_blas_threads(1); }
SparseCholesky::~SparseCholesky() = default;

void SparseCholesky::analyze(int32_t n, const int32_t* outer, const int32_t* inner) {
  Impl& s = *impl_;
  const auto t0 = Clock::now();
  if (s.factor != nullptr) cholmod_free_factor(&s.factor, &s.common);
  s.numeric = false;
  s.single.clear();
  s.n = n;
  s.outer.assign(outer, outer + n + 1);
  s.inner.assign(inner, inner + outer[n]);
  cholmod_sparse a = s.view(nullptr);
  s.factor = cholmod_analyze(&a, &s.common);
  if (s.factor == nullptr || s.common.status < CHOLMOD_OK) s.fail("the analysis (ordering) of the sparse Cholesky factor");
  s.analyze_s = seconds_since(t0);
}

bool SparseCholesky::analyzed() const { return impl_->factor != nullptr; }

int64_t SparseCholesky::factor_bytes() const {
  const cholmod_factor* f = impl_->factor;
  if (f == nullptr) return 0;
  // Supernodal: xsize reals and ssize integers; simplicial: the analysis' nnz estimate.
  return f->is_super ? static_cast<int64_t>(f->xsize) * 8 + static_cast<int64_t>(f->ssize) * 4
                     : static_cast<int64_t>(impl_->common.lnz) * 12;
}

int64_t SparseCholesky::factor_nonzeros() const {
  const cholmod_factor* f = impl_->factor;
  if (f == nullptr) return 0;
  return f->is_super ? static_cast<int64_t>(f->xsize) : static_cast<int64_t>(impl_->common.lnz);
}

int64_t SparseCholesky::factorize(const double* values) {
  Impl& s = *impl_;
  if (s.factor == nullptr) throw RuntimeError(s.where + ": factorize() before analyze()");
  const auto t0 = Clock::now();
  check_allocation(1, static_cast<uint64_t>(factor_bytes()), s.where,
                   "the sparse Cholesky factor of " + std::to_string(s.n) + " unknowns (" +
                       std::to_string(factor_nonzeros()) + " non-zeros)");
  cholmod_sparse a = s.view(values);
  s.single.clear();
  const int ok = cholmod_factorize(&a, s.factor, &s.common);
  s.factor_s = seconds_since(t0);
  if (s.common.status == CHOLMOD_NOT_POSDEF) {
    s.numeric = false;
    return static_cast<int64_t>(s.factor->minor);
  }
  if (!ok || s.common.status < CHOLMOD_OK) s.fail("the sparse Cholesky factorisation");
  s.numeric = true;
  return -1;
}

bool SparseCholesky::factorized() const { return impl_->numeric; }

void SparseCholesky::solve(const double* b, double* x) const { solve(b, x, 1); }

void SparseCholesky::solve(const double* b, double* x, int32_t k) const {
  Impl& s = *impl_;
  if (!s.numeric) throw RuntimeError(s.where + ": solve() without a factor");
  cholmod_dense rhs{};
  rhs.nrow = static_cast<size_t>(s.n);
  rhs.ncol = static_cast<size_t>(k);
  rhs.nzmax = rhs.nrow * rhs.ncol;
  rhs.d = rhs.nrow;
  rhs.x = const_cast<double*>(b);
  rhs.xtype = CHOLMOD_REAL;
  rhs.dtype = CHOLMOD_DOUBLE;
  cholmod_dense* sol = cholmod_solve(CHOLMOD_A, s.factor, &rhs, &s.common);
  if (sol == nullptr || s.common.status < CHOLMOD_OK) {
    if (sol != nullptr) cholmod_free_dense(&sol, &s.common);
    s.fail("the solve with the sparse Cholesky factor");
  }
  std::memcpy(x, sol->x, sizeof(double) * rhs.nzmax);
  cholmod_free_dense(&sol, &s.common);
}

void SparseCholesky::make_single() {
  Impl& s = *impl_;
  if (!s.numeric || !s.factor->is_super) throw RuntimeError(s.where + ": make_single() needs a supernodal factor");
  const cholmod_factor& f = *s.factor;
  const auto* super = static_cast<const int32_t*>(f.super);
  const auto* pi = static_cast<const int32_t*>(f.pi);
  const auto* px = static_cast<const int32_t*>(f.px);
  const auto* x = static_cast<const double*>(f.x);
  s.single.assign(f.xsize, 0.0f);
  std::vector<double> diag, w;
  const double one = 1;
  for (size_t k = 0; k < f.nsuper; ++k) {
    const int ncols = super[k + 1] - super[k], nrows = pi[k + 1] - pi[k];
    // W_k = [L_kk; L_bk] L_kk^-1: L_kk^-1 solved from the identity (its upper triangle zero), the rows
    // below by the same triangular solve from the right.
    const double* block = x + px[k];
    diag.assign(static_cast<size_t>(ncols) * ncols, 0.0);
    for (int j = 0; j < ncols; ++j)
      for (int i = j; i < ncols; ++i) diag[static_cast<size_t>(i + ncols * j)] = block[i + nrows * j];
    w.assign(static_cast<size_t>(nrows) * ncols, 0.0);
    for (int j = 0; j < ncols; ++j) w[static_cast<size_t>(j + nrows * j)] = 1;
    for (int j = 0; j < ncols; ++j)
      for (int i = ncols; i < nrows; ++i) w[static_cast<size_t>(i + nrows * j)] = block[i + nrows * j];
    // Top: L_kk X = I. Below: X L_kk = L_bk.
    dtrsm_("L", "L", "N", "N", &ncols, &ncols, &one, diag.data(), &ncols, w.data(), &nrows);
    const int below = nrows - ncols;
    if (below > 0) dtrsm_("R", "L", "N", "N", &below, &ncols, &one, diag.data(), &ncols, w.data() + ncols, &nrows);
    float* out = s.single.data() + px[k];
    for (size_t i = 0; i < w.size(); ++i) out[i] = static_cast<float>(w[i]);
  }
  s.schedule = substitution_schedule(f);
}

bool SparseCholesky::has_single() const { return !impl_->single.empty(); }

// L L^T = P A P^T, L in supernodes: supernode k holds columns super[k] .. super[k+1] - 1, its rows
// s[pi[k] .. pi[k+1]) (the first ones its own columns), its values a column-major block at px[k] with
// the row count as leading dimension (CHOLMOD's cholmod_factor). make_single() stored each block as
// W_k = [L_kk; L_bk] L_kk^-1, so that a supernode's step of each substitution is one matrix-vector
// product (a triangular solve with a small block is many tiny BLAS steps; a product streams the block):
//   forward  (L y = P b):   z = W_k y_k, then y_k = z_top, y_below -= z_below;
//   backward (L^T z = y):   y_k = W_k^T [y_k; -y_below]   (= L_kk^-T (y_k - L_bk^T y_below)).
namespace {

// Supernode k's place in the factor: its first column, its column and row counts, its block W_k (in
// the single-precision form `lx`, column-major, the row count as leading dimension) and its rows.
struct SupernodeBlock {
  int first, ncols, nrows;
  const float* w;
  const int32_t* rows;
};

inline SupernodeBlock supernode_block(const cholmod_factor& f, const float* lx, int32_t k) {
  const auto* super = static_cast<const int32_t*>(f.super);
  const auto* pi = static_cast<const int32_t*>(f.pi);
  const auto* px = static_cast<const int32_t*>(f.px);
  return {super[k], super[k + 1] - super[k], pi[k + 1] - pi[k], lx + px[k], static_cast<const int32_t*>(f.s) + pi[k]};
}

// out = W^T in (trans "T") or W in ("N"), in float.
inline void block_product(const char* trans, const SupernodeBlock& b, const float* in, float* out) {
  const int one = 1;
  const float fone = 1, fzero = 0;
  sgemv_(trans, &b.nrows, &b.ncols, &fone, b.w, &b.nrows, in, &one, &fzero, out, &one);
}

// One supernode's step of the forward substitution: z = W_k y_k into z (nrows), y_k = z_top, and the
// rows below less z_below: into y where `owner` says they are the group's own (or any, for the top:
// g < 0), else into the group's buffer `top_update` (the top's rows, summed in later).
inline void forward_step(const cholmod_factor& f, const float* lx, int32_t k, int g, const int8_t* owner, float* y, float* z,
                         float* top_update) {
  const SupernodeBlock b = supernode_block(f, lx, k);
  float* yk = y + b.first;
  block_product("N", b, yk, z);
  for (int i = 0; i < b.ncols; ++i) yk[i] = z[i];
  for (int i = b.ncols; i < b.nrows; ++i) {
    if (g < 0 || owner[b.rows[i]] == g) {
      y[b.rows[i]] -= z[i];
    } else {
      top_update[b.rows[i]] += z[i];
    }
  }
}

// One supernode's step of the backward substitution: y_k = W_k^T [y_k; -y_below] (z: nrows of scratch).
inline void backward_step(const cholmod_factor& f, const float* lx, int32_t k, float* y, float* z) {
  const SupernodeBlock b = supernode_block(f, lx, k);
  float* yk = y + b.first;
  for (int i = 0; i < b.ncols; ++i) z[i] = yk[i];
  for (int i = b.ncols; i < b.nrows; ++i) z[i] = -y[b.rows[i]];
  block_product("T", b, z, yk);
}

}  // namespace

void SparseCholesky::solve_single(const double* b, double* x, int threads) const {
  const Impl& s = *impl_;
  if (s.single.empty()) throw RuntimeError(s.where + ": solve_single() without make_single()");
  const cholmod_factor& f = *s.factor;
  const SubstitutionSchedule& plan = s.schedule;
  const auto* perm = static_cast<const int32_t*>(f.Perm);
  const float* lx = s.single.data();
  const auto n = static_cast<size_t>(s.n);
  std::vector<float>& y = s.work;
  y.resize(n);
  for (size_t i = 0; i < n; ++i) y[i] = static_cast<float>(b[perm[i]]);
  // Per group: n values of its own (the top's rows that it updates; zero elsewhere) and the scratch z.
  for (auto& buffer : s.group_buffers) {
    buffer.resize(n + plan.max_rows);
    for (int32_t c : plan.top_rows) buffer[static_cast<size_t>(c)] = 0;
  }
  const int t = std::clamp(threads, 1, kSubstitutionGroups);
  // Forward: the groups' subtrees, then the top with their updates summed in group order.
#pragma omp parallel for schedule(static, 1) num_threads(t)
  for (int g = 0; g < kSubstitutionGroups; ++g) {
    float* own = s.group_buffers[g].data();
    for (int32_t k : plan.groups[g]) forward_step(f, lx, k, g, plan.owner.data(), y.data(), own + n, own);
  }
  for (int32_t c : plan.top_rows)
    for (const auto& buffer : s.group_buffers) y[static_cast<size_t>(c)] -= buffer[static_cast<size_t>(c)];
  float* z = s.group_buffers[0].data() + n;
  for (int32_t k : plan.top) forward_step(f, lx, k, -1, plan.owner.data(), y.data(), z, nullptr);
  // Backward: the top, then the groups (each reads only its own rows and the top's).
  for (auto k = plan.top.rbegin(); k != plan.top.rend(); ++k) backward_step(f, lx, *k, y.data(), z);
#pragma omp parallel for schedule(static, 1) num_threads(t)
  for (int g = 0; g < kSubstitutionGroups; ++g) {
    float* own = s.group_buffers[g].data() + n;
    for (auto k = plan.groups[g].rbegin(); k != plan.groups[g].rend(); ++k) backward_step(f, lx, *k, y.data(), own);
  }
  for (size_t i = 0; i < n; ++i) x[perm[i]] = static_cast<double>(y[i]);
}

int32_t SparseCholesky::size() const { return impl_->n; }
double SparseCholesky::analyze_seconds() const { return impl_->analyze_s; }
double SparseCholesky::factor_seconds() const { return impl_->factor_s; }

}  // namespace ctsurg::sim
