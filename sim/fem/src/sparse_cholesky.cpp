#include "sparse_cholesky.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/memory_guard.h"
#include "ctsurg/core/elapsed_seconds.h"

#include <cholmod.h>
#include <dlfcn.h>

#include <chrono>
#include <cstring>
#include <vector>

// The BLAS's single-precision matrix-vector product and triangular solve (Fortran interface: every
// BLAS has it; the same library CHOLMOD's double-precision substitutions run on).
extern "C" {
void sgemv_(const char* trans, const int* m, const int* n, const float* alpha, const float* a, const int* lda, const float* x,
            const int* incx, const float* beta, float* y, const int* incy);
void strsv_(const char* uplo, const char* trans, const char* diag, const int* n, const float* a, const int* lda, float* x,
            const int* incx);
}

namespace ctsurg::sim {
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
  std::vector<float> single;       // make_single(): the factor's blocks in float (empty: none)
  mutable std::vector<float> work, gathered;
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
  const auto* x = static_cast<const double*>(s.factor->x);
  s.single.assign(x, x + s.factor->xsize);
}

bool SparseCholesky::has_single() const { return !impl_->single.empty(); }

// L L^T = P A P^T, L in supernodes: supernode k holds columns super[k] .. super[k+1] - 1, its rows
// s[pi[k] .. pi[k+1]) (the first ones its own columns), its values a column-major block at px[k] with
// the row count as leading dimension (CHOLMOD's cholmod_factor). x = P^T L^-T L^-1 P b, supernode by
// supernode as CHOLMOD's own solve: the diagonal block by strsv, the rows below by sgemv, in float.
void SparseCholesky::solve_single(const double* b, double* x) const {
  const Impl& s = *impl_;
  if (s.single.empty()) throw RuntimeError(s.where + ": solve_single() without make_single()");
  const cholmod_factor& f = *s.factor;
  const auto* super = static_cast<const int32_t*>(f.super);
  const auto* pi = static_cast<const int32_t*>(f.pi);
  const auto* px = static_cast<const int32_t*>(f.px);
  const auto* rows = static_cast<const int32_t*>(f.s);
  const auto* perm = static_cast<const int32_t*>(f.Perm);
  const float* lx = s.single.data();
  const auto nsuper = static_cast<int32_t>(f.nsuper);
  std::vector<float>& y = s.work;
  std::vector<float>& t = s.gathered;
  y.resize(static_cast<size_t>(s.n));
  for (int32_t i = 0; i < s.n; ++i) y[static_cast<size_t>(i)] = static_cast<float>(b[perm[i]]);
  const int one = 1;
  const float fone = 1, fzero = 0, fminus = -1;
  // Forward: L y = P b.
  for (int32_t k = 0; k < nsuper; ++k) {
    const int k1 = super[k], ncols = super[k + 1] - k1, nrows = pi[k + 1] - pi[k], below = nrows - ncols;
    const float* block = lx + px[k];
    float* yk = y.data() + k1;
    strsv_("L", "N", "N", &ncols, block, &nrows, yk, &one);
    if (below == 0) continue;
    t.resize(static_cast<size_t>(below));
    sgemv_("N", &below, &ncols, &fone, block + ncols, &nrows, yk, &one, &fzero, t.data(), &one);
    const int32_t* r = rows + pi[k] + ncols;
    for (int i = 0; i < below; ++i) y[static_cast<size_t>(r[i])] -= t[static_cast<size_t>(i)];
  }
  // Backward: L^T z = y.
  for (int32_t k = nsuper - 1; k >= 0; --k) {
    const int k1 = super[k], ncols = super[k + 1] - k1, nrows = pi[k + 1] - pi[k], below = nrows - ncols;
    const float* block = lx + px[k];
    float* yk = y.data() + k1;
    if (below > 0) {
      t.resize(static_cast<size_t>(below));
      const int32_t* r = rows + pi[k] + ncols;
      for (int i = 0; i < below; ++i) t[static_cast<size_t>(i)] = y[static_cast<size_t>(r[i])];
      sgemv_("T", &below, &ncols, &fminus, block + ncols, &nrows, t.data(), &one, &fone, yk, &one);
    }
    strsv_("L", "T", "N", &ncols, block, &nrows, yk, &one);
  }
  for (int32_t i = 0; i < s.n; ++i) x[perm[i]] = static_cast<double>(y[static_cast<size_t>(i)]);
}

int32_t SparseCholesky::size() const { return impl_->n; }
double SparseCholesky::analyze_seconds() const { return impl_->analyze_s; }
double SparseCholesky::factor_seconds() const { return impl_->factor_s; }

}  // namespace ctsurg::sim
