// Jacobi-preconditioned conjugate gradients in double on a CUDA device, for the static FEM's linear
// systems K du = r (fem_static_solver.cpp with Backend::cuda; the FEM paper, section 4, runs its CG on
// the GPU). Plain C++ (no CUDA types): device_conjugate_gradient_cuda.cu implements it with nvcc, and
// fem_device_stubs.cpp replaces it in a build without CUDA (the constructor refuses).
//
// The iteration is Eigen::ConjugateGradient's (Eigen 3.4, IterativeLinearSolvers/ConjugateGradient.h)
// with Eigen::DiagonalPreconditioner, step for step, so that CPU and GPU report comparable iteration
// counts:
//   x = 0, r = b, threshold = max(tol^2 |b|^2, DBL_MIN); stop at once if |r|^2 < threshold;
//   p = M^-1 r (M^-1 = 1 / diagonal, or 1 where the diagonal is missing or 0), rho = r.p;
//   for i = 0 .. max_iterations - 1:
//     q = A p; alpha = rho / p.q; x += alpha p; r -= alpha q;
//     stop if |r|^2 < threshold (i iterations are counted, as Eigen counts);
//     z = M^-1 r; rho' = r.z; p = z + (rho' / rho) p; rho = rho'.
// The dot products are device sums in a fixed order (device_reduction.cuh), different from Eigen's,
// so the two agree to rounding, and iteration counts may differ by a few.
//
// The matrix is CSR (row offsets, column indices sorted per row, values; both triangles stored, as
// fem_static_solver.cpp's RowMajor Eigen::SparseMatrix): the pattern is uploaded once, the values on
// every assembly. The product is one warp per row (CSR-vector) with a fixed shuffle-tree sum per row.
#pragma once

#include <cstdint>
#include <memory>

namespace ctsurg::sim {

struct DeviceCgResult {
  int64_t iterations = 0;         // Eigen's count (see above)
  double relative_residual = 0;   // |r| / |b| of the recursively updated residual (Eigen's error())
};

class DeviceConjugateGradient {
 public:
  // Selects CUDA device 0. Throws InputError(where, "backend", ...) where cuda cannot run (no CUDA
  // build or no device).
  explicit DeviceConjugateGradient(const char* where);
  ~DeviceConjugateGradient();
  DeviceConjugateGradient(const DeviceConjugateGradient&) = delete;
  DeviceConjugateGradient& operator=(const DeviceConjugateGradient&) = delete;

  // The sparsity pattern of a rows x rows matrix: offsets (rows + 1, offsets[0] = 0), columns
  // (offsets[rows] entries, each row's sorted). Replaces the previous pattern and values.
  void set_pattern(int32_t rows, const int32_t* offsets, const int32_t* columns);
  bool has_pattern() const { return rows_ >= 0; }
  // The values in the pattern's order (offsets[rows] of them); the matrix must be symmetric positive
  // definite for CG to converge. Also computes the preconditioner (the inverse diagonal).
  void set_values(const double* values);
  // Solves A x = b (rows values each, host memory) from x = 0 with the rule above: tolerance in (0, 1),
  // max_iterations >= 0. Blocks until done.
  DeviceCgResult solve(const double* b, double* x, double tolerance, int64_t max_iterations);

  struct Device;  // CUDA handles and buffers (device_conjugate_gradient_cuda.cu)

 private:
  std::unique_ptr<Device> device_;
  int32_t rows_ = -1;
};

}  // namespace ctsurg::sim
