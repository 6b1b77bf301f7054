// Sparse Cholesky factorisation of a symmetric positive definite matrix (the FEM's stiffness and
// tangent matrices): SuiteSparse's CHOLMOD, supernodal, with its fill-reducing ordering (AMD, or METIS
// nested dissection when AMD fills too much), over BLAS (OpenBLAS on Debian). Chosen by measurement
// against Eigen's SimplicialLLT (bench/bench_sparse_factorisation.cpp, docs/fem.md "Direct solves"):
// on the Kuhn cube of 4,913 nodes the numeric factorisation takes 0.25 s against 2.3 s, on 15,625
// nodes 1.5 s against 50 s.
//
// The symbolic analysis (ordering, elimination tree, supernodes) is done once per sparsity pattern and
// kept; each factorize() reuses it for new values. The matrix is given as compressed rows (or
// columns: it is symmetric) of both triangles; CHOLMOD reads its lower triangle.
//
// Errors: a matrix that is not positive definite is reported by factorize() (the failing column), a
// factor that would not fit in memory is refused before it is made (core/memory_guard.h) with its size
// in the message, and CHOLMOD's own messages are not printed: its status becomes a RuntimeError.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

namespace ctsurg::sim {

class SparseCholesky {
 public:
  // `where` names the solver in messages ("fem static", ...). The BLAS runs on one thread (see
  // sparse_cholesky.cpp: results independent of the core count).
  explicit SparseCholesky(std::string where);
  ~SparseCholesky();
  SparseCholesky(const SparseCholesky&) = delete;
  SparseCholesky& operator=(const SparseCholesky&) = delete;

  // Orders and analyses the n x n pattern (outer: n + 1 offsets, inner: indices, both triangles,
  // sorted within each row); forgets any factor. The arrays need not outlive the call.
  void analyze(int32_t n, const int32_t* outer, const int32_t* inner);
  bool analyzed() const;
  // The numeric factor's size in bytes, known from the analysis (before factorize()).
  int64_t factor_bytes() const;
  int64_t factor_nonzeros() const;

  // Factorises the matrix with the analysed pattern and these values (one per entry of `inner`).
  // Returns -1 on success, or the column (0-based) where it was found not positive definite (the
  // factor is then unusable). Throws RuntimeError when the factor does not fit in memory.
  int64_t factorize(const double* values);
  bool factorized() const;

  // x = A^-1 b (n values each; b and x may be the same array).
  void solve(const double* b, double* x) const;
  // X = A^-1 B for k right-hand sides (column-major n x k), in one pass over the factor.
  void solve(const double* b, double* x, int32_t k) const;

  // A single-precision form of the current factor, for solves that only precondition (the quasi-Newton
  // iteration's initial inverse Hessian, fem_quasi_newton.cpp): each supernode's block stored as
  // [L_kk; L_bk] L_kk^-1 (its diagonal block inverted in double, then rounded), so that each step of the
  // forward and back substitutions is one float matrix-vector product instead of a triangular solve of
  // many tiny steps; half the memory traffic of solve(). To float's precision times the matrix's
  // conditioning (not checked here: its callers only precondition, and converge on the double-precision
  // residual; measured 4e-7 relative on the live heart's rest stiffness). make_single() after factorize()
  // (RuntimeError without a supernodal factor); the next factorize() or analyze() forgets it.
  // The substitutions run over two disjoint subtrees of the elimination tree at once (`threads`: 1 or
  // more; more than 2 use 2), then over the supernodes above them; the result's bits do not depend on
  // `threads` (the split is fixed by the factor's structure).
  void make_single();
  bool has_single() const;
  void solve_single(const double* b, double* x, int threads) const;

  int32_t size() const;
  double analyze_seconds() const;   // the last analysis
  double factor_seconds() const;    // the last factorisation

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ctsurg::sim
