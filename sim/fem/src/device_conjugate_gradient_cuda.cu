// DeviceConjugateGradient (device_conjugate_gradient.h): Jacobi-preconditioned CG in double on a CUDA
// device, Eigen's iteration step for step (the header lists it).
//
// Memory: the CSR pattern (offsets #rows + 1, columns #nnz, int32) and values (#nnz double) stay on the
// device across solves (values replaced per assembly); x, r, p, z, q = A p and the inverse diagonal
// (#rows double each); two arrays of per-block partial sums; the scalars (alpha, beta, rho, the
// threshold, the iteration count and a `done` flag) in device memory, so that no iteration waits for
// the host.
//
// One iteration = 5 launches: q = A p with the partial sums of p.q (one warp per row); alpha (one
// block); x, r, z = M^-1 r with the partial sums of r.r and r.z; the convergence test, rho and beta
// (one block); p = z + beta p. Every kernel returns at once when `done` is set, so the host queues
// kBatch iterations (release builds: one CUDA graph replay), then reads the scalars once (pinned
// memory, 64 bytes): the iteration count is Eigen's exactly, at the price of at most kBatch - 1
// iterations of empty launches after convergence. Sums are deterministic (device_reduction.cuh), so a
// solve gives the same bits on every run. Debug builds launch directly and synchronise after each
// launch.
#include "device_conjugate_gradient.h"

#include "ctsurg/sim/base/cuda_support.cuh"
#include "ctsurg/sim/base/device_reduction.cuh"

#include "ctsurg/sim/base/backend.h"

#include <cfloat>
#include <cmath>

namespace ctsurg::sim {
namespace {

constexpr int kBlock = 256;                      // threads per block
constexpr int kWarp = 32;
constexpr int kRowsPerBlock = kBlock / kWarp;    // the product: one warp per row
constexpr int64_t kBatch = 32;                   // iterations queued between reads of `done`
#if defined(NDEBUG)
constexpr bool kGraphs = true;
#else
constexpr bool kGraphs = false;  // debug: direct launches, each synchronised
#endif

struct CsrView {
  const int32_t* offsets;  // rows + 1
  const int32_t* columns;  // nnz
  const double* values;    // nnz
  int32_t rows;
};

// The iteration's scalars (Eigen's names in the comments).
struct Scalars {
  double threshold;       // max(tol^2 |b|^2, DBL_MIN)
  double rhs_norm2;       // |b|^2 (rhsNorm2)
  double residual_norm2;  // |r|^2 after the last update (residualNorm2)
  double rho;             // r.z of the current direction (absNew)
  double alpha, beta;
  int64_t iterations;     // i
  int64_t max_iterations; // maxIters
  int32_t done;           // 1: converged or out of iterations; every later kernel returns
};

// Eigen::DiagonalPreconditioner: 1 / a_ii, or 1 where row i has no diagonal entry or a zero one.
__global__ void __launch_bounds__(kBlock) inverse_diagonal_kernel(CsrView a, double* inv_diag) {
  const int32_t i = static_cast<int32_t>(blockIdx.x * blockDim.x + threadIdx.x);
  if (i >= a.rows) return;
  double d = 1;
  for (int32_t k = a.offsets[i]; k < a.offsets[i + 1]; ++k)
    if (a.columns[k] == i) {
      if (a.values[k] != 0) d = 1 / a.values[k];
      break;
    }
  inv_diag[i] = d;
}

// r = b is already in r (x = 0): p = M^-1 r and the partial sums of r.r and r.p.
__global__ void __launch_bounds__(kBlock) start_kernel(const double* r, const double* inv_diag, double* p, int32_t rows,
                                                       double* partial_rr, double* partial_rp) {
  __shared__ double shared[kBlock];
  const int32_t i = static_cast<int32_t>(blockIdx.x * blockDim.x + threadIdx.x);
  double rr = 0, rp = 0;
  if (i < rows) {
    const double pi = inv_diag[i] * r[i];
    p[i] = pi;
    rr = r[i] * r[i];
    rp = r[i] * pi;
  }
  rr = cuda::block_sum<kBlock>(rr, shared);
  rp = cuda::block_sum<kBlock>(rp, shared);
  if (threadIdx.x == 0) partial_rr[blockIdx.x] = rr, partial_rp[blockIdx.x] = rp;
}

__global__ void __launch_bounds__(kBlock) start_scalars_kernel(const double* partial_rr, const double* partial_rp,
                                                               int64_t count, double tolerance,
                                                               int64_t max_iterations, Scalars* s) {
  __shared__ double shared[kBlock];
  const double rr = cuda::sum_in_one_block<kBlock>(partial_rr, count, shared);
  const double rp = cuda::sum_in_one_block<kBlock>(partial_rp, count, shared);
  if (threadIdx.x != 0) return;
  s->rhs_norm2 = rr;
  s->residual_norm2 = rr;  // r = b - A 0 = b
  s->threshold = fmax(tolerance * tolerance * rr, DBL_MIN);
  s->rho = rp;
  s->alpha = 0, s->beta = 0;
  s->iterations = 0;
  s->max_iterations = max_iterations;
  s->done = rr == 0 || rr < s->threshold || max_iterations == 0;
}

// q = A p (one warp per row: lanes take every 32nd entry in order, then a fixed shuffle tree) and the
// partial sums of p.q. A warp's row is the same for its 32 lanes, so the shuffles see full warps.
__global__ void __launch_bounds__(kBlock) product_kernel(CsrView a, const double* p, double* q, double* partial_pq,
                                                         const Scalars* s) {
  __shared__ double shared[kBlock];
  if (s->done) return;  // the same for every thread: no barrier is skipped by some
  const int lane = static_cast<int>(threadIdx.x) % kWarp;
  const int64_t row = static_cast<int64_t>(blockIdx.x) * kRowsPerBlock + threadIdx.x / kWarp;
  double pq = 0;
  if (row < a.rows) {
    double v = 0;
    for (int32_t k = a.offsets[row] + lane; k < a.offsets[row + 1]; k += kWarp) v += a.values[k] * p[a.columns[k]];
#pragma unroll
    for (int offset = kWarp / 2; offset > 0; offset /= 2) v += __shfl_down_sync(0xffffffffu, v, offset);
    if (lane == 0) {
      q[row] = v;
      pq = p[row] * v;
    }
  }
  pq = cuda::block_sum<kBlock>(pq, shared);
  if (threadIdx.x == 0) partial_pq[blockIdx.x] = pq;
}

__global__ void __launch_bounds__(kBlock) alpha_kernel(const double* partial_pq, int64_t count, Scalars* s) {
  __shared__ double shared[kBlock];
  if (s->done) return;
  const double pq = cuda::sum_in_one_block<kBlock>(partial_pq, count, shared);
  if (threadIdx.x == 0) s->alpha = s->rho / pq;
}

// x += alpha p, r -= alpha q, z = M^-1 r, and the partial sums of r.r and r.z.
__global__ void __launch_bounds__(kBlock) update_kernel(double* x, double* r, const double* p, const double* q,
                                                        const double* inv_diag, double* z, int32_t rows,
                                                        double* partial_rr, double* partial_rz, const Scalars* s) {
  __shared__ double shared[kBlock];
  if (s->done) return;
  const int32_t i = static_cast<int32_t>(blockIdx.x * blockDim.x + threadIdx.x);
  double rr = 0, rz = 0;
  if (i < rows) {
    const double alpha = s->alpha;
    x[i] += alpha * p[i];
    const double ri = r[i] - alpha * q[i];
    const double zi = inv_diag[i] * ri;
    r[i] = ri;
    z[i] = zi;
    rr = ri * ri;
    rz = ri * zi;
  }
  rr = cuda::block_sum<kBlock>(rr, shared);
  rz = cuda::block_sum<kBlock>(rz, shared);
  if (threadIdx.x == 0) partial_rr[blockIdx.x] = rr, partial_rz[blockIdx.x] = rz;
}

// The convergence test, then rho and beta for the next direction; counts the iteration.
__global__ void __launch_bounds__(kBlock) test_kernel(const double* partial_rr, const double* partial_rz, int64_t count,
                                                      Scalars* s) {
  __shared__ double shared[kBlock];
  if (s->done) return;
  const double rr = cuda::sum_in_one_block<kBlock>(partial_rr, count, shared);
  const double rz = cuda::sum_in_one_block<kBlock>(partial_rz, count, shared);
  if (threadIdx.x != 0) return;
  s->residual_norm2 = rr;
  if (rr < s->threshold) {
    s->done = 1;
    return;
  }
  s->beta = rz / s->rho;
  s->rho = rz;
  s->iterations += 1;
  if (s->iterations >= s->max_iterations) s->done = 1;
}

__global__ void __launch_bounds__(kBlock) direction_kernel(double* p, const double* z, int32_t rows, const Scalars* s) {
  if (s->done) return;
  const int32_t i = static_cast<int32_t>(blockIdx.x * blockDim.x + threadIdx.x);
  if (i < rows) p[i] = z[i] + s->beta * p[i];
}

}  // namespace

struct DeviceConjugateGradient::Device {
  int ordinal = 0;
  cuda::Stream stream;
  cuda::DeviceBuffer<int32_t> offsets, columns;
  cuda::DeviceBuffer<double> values, inv_diag, x, r, p, z, q, partial_a, partial_b;
  cuda::DeviceBuffer<Scalars> scalars;  // one element
  cuda::PinnedValue<Scalars> scalars_host;
  cuda::Graph batch;  // kBatch iterations
  int32_t rows = 0;

  ~Device() { cuda::release_check(cudaStreamSynchronize(stream), "cudaStreamSynchronize"); }

  CsrView matrix() const { return {offsets.data(), columns.data(), values.data(), rows}; }

  void launch_iteration() {
    const unsigned row_blocks = cuda::blocks_for(rows, kBlock), product_blocks = cuda::blocks_for(rows, kRowsPerBlock);
    product_kernel<<<product_blocks, kBlock, 0, stream>>>(matrix(), p.data(), q.data(), partial_a.data(), scalars.data());
    CTSURG_CUDA_LAUNCHED(stream);
    alpha_kernel<<<1, kBlock, 0, stream>>>(partial_a.data(), product_blocks, scalars.data());
    CTSURG_CUDA_LAUNCHED(stream);
    update_kernel<<<row_blocks, kBlock, 0, stream>>>(x.data(), r.data(), p.data(), q.data(), inv_diag.data(), z.data(), rows,
                                                     partial_a.data(), partial_b.data(), scalars.data());
    CTSURG_CUDA_LAUNCHED(stream);
    test_kernel<<<1, kBlock, 0, stream>>>(partial_a.data(), partial_b.data(), row_blocks, scalars.data());
    CTSURG_CUDA_LAUNCHED(stream);
    direction_kernel<<<row_blocks, kBlock, 0, stream>>>(p.data(), z.data(), rows, scalars.data());
    CTSURG_CUDA_LAUNCHED(stream);
  }

  void launch_batch() {
    if (!kGraphs) {
      for (int64_t k = 0; k < kBatch; ++k) launch_iteration();
      return;
    }
    if (!batch) batch.capture(stream, [&] {
        for (int64_t k = 0; k < kBatch; ++k) launch_iteration();
      });
    batch.launch(stream);
  }
};

DeviceConjugateGradient::DeviceConjugateGradient(const char* where) {
  if (!backend_available(Backend::cuda)) require_backend(Backend::cuda, where);  // throws why
  cuda::use_device(0);
  device_ = std::make_unique<Device>();
  device_->scalars.resize(1);
}

DeviceConjugateGradient::~DeviceConjugateGradient() = default;

void DeviceConjugateGradient::set_pattern(int32_t rows, const int32_t* offsets, const int32_t* columns) {
  Device& d = *device_;
  cuda::use_device(d.ordinal);
  const auto n = static_cast<std::size_t>(rows), nnz = static_cast<std::size_t>(offsets[rows]);
  d.batch.release();  // it holds the previous buffers
  d.offsets.upload(offsets, n + 1, d.stream);
  d.columns.upload(columns, nnz, d.stream);
  d.values.resize(nnz);
  for (auto* v : {&d.inv_diag, &d.x, &d.r, &d.p, &d.z, &d.q}) v->resize(n);
  d.partial_a.resize(cuda::blocks_for(rows, kRowsPerBlock));  // the most blocks of any kernel
  d.partial_b.resize(cuda::blocks_for(rows, kRowsPerBlock));
  d.rows = rows;
  d.stream.synchronize();  // the host arrays may go away after return
  rows_ = rows;
}

void DeviceConjugateGradient::set_values(const double* values) {
  Device& d = *device_;
  cuda::use_device(d.ordinal);
  d.values.upload(values, d.values.size(), d.stream);  // same size: in place, the recorded batch stays valid
  if (d.rows > 0) {
    inverse_diagonal_kernel<<<cuda::blocks_for(d.rows, kBlock), kBlock, 0, d.stream>>>(d.matrix(), d.inv_diag.data());
    CTSURG_CUDA_LAUNCHED(d.stream);
  }
  d.stream.synchronize();
}

DeviceCgResult DeviceConjugateGradient::solve(const double* b, double* x, double tolerance, int64_t max_iterations) {
  Device& d = *device_;
  cuda::use_device(d.ordinal);
  if (d.rows == 0) return {};
  const auto n = static_cast<std::size_t>(d.rows);
  const unsigned row_blocks = cuda::blocks_for(d.rows, kBlock);
  d.r.upload(b, n, d.stream);
  d.x.zero(d.stream);
  start_kernel<<<row_blocks, kBlock, 0, d.stream>>>(d.r.data(), d.inv_diag.data(), d.p.data(), d.rows, d.partial_a.data(),
                                                   d.partial_b.data());
  CTSURG_CUDA_LAUNCHED(d.stream);
  start_scalars_kernel<<<1, kBlock, 0, d.stream>>>(d.partial_a.data(), d.partial_b.data(), row_blocks, tolerance,
                                                   max_iterations, d.scalars.data());
  CTSURG_CUDA_LAUNCHED(d.stream);
  // After max_iterations queued iterations the device has set `done` itself (out of iterations).
  for (int64_t queued = 0; queued < max_iterations; queued += kBatch) {
    d.launch_batch();
    d.scalars.download(d.scalars_host.get(), 1, d.stream);
    d.stream.synchronize();
    if (d.scalars_host->done) break;
  }
  d.x.download(x, n, d.stream);
  d.scalars.download(d.scalars_host.get(), 1, d.stream);
  d.stream.synchronize();
  const Scalars& s = *d.scalars_host;
  return {s.iterations, s.rhs_norm2 > 0 ? std::sqrt(s.residual_norm2 / s.rhs_norm2) : 0.0};
}

}  // namespace ctsurg::sim
