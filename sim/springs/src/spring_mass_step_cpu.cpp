// The CPU build of the step kernels: OpenMP threads over static particle ranges (boundaries on
// multiples of 64), and SIMD lanes across the 32 particles of a chunk, one spring direction (grid) or
// row slot (explicit) at a time; the last partial chunk runs the per-particle kernel a GPU thread
// would. Every path sums a particle's springs in the same order, so the results are the same bits
// for any thread count. On x86-64 with GCC the range loops are compiled three times (AVX-512, AVX2,
// baseline SSE2) and the loader picks the best the CPU has (target_clones); contraction into FMA is
// off for this file (CMakeLists.txt) so every variant, and every scalar remainder, computes the same
// bits.
#include "ctsurg/sim/springs/kernels/particle_normals_impl.h"
#include "ctsurg/sim/springs/kernels/spring_forces_impl.h"
#include "ctsurg/sim/springs/kernels/verlet_step_impl.h"
#include "spring_cpu_kernels.h"

#include <omp.h>

#include <algorithm>
#include <cstdint>

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(__SANITIZE_ADDRESS__)
#define CTSURG_CPU_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define CTSURG_CPU_CLONES
#endif

namespace ctsurg::sim::cpu {
namespace {

// Particles per chunk of the grid kernel (the model's chunk index uses the same): a divisor of the
// 64-particle partition, so chunks fall on the same particles for any thread count.
constexpr int32_t kChunk = kGridChunk;
static_assert(64 % kChunk == 0);

template <bool kDamping, bool kNormals>
inline __attribute__((always_inline)) void grid_range(const SpringGridView& grid, const ParticleStateView& state,
                                                      const VerletConstants& constants, Real* nx, Real* ny, Real* nz,
                                                      int32_t begin, int32_t end) {
  // Local copies: the vectoriser must see that the view's pointers do not change inside the loops.
  const SpringGridView g = grid;
  const ParticleStateView s = state;
  const VerletConstants c = constants;
  int32_t i0 = begin;
  // Chunks of 32 particles, direction by direction. Where the springs in direction d lead to
  // consecutive particles (rows of a solid region: most chunks), the neighbours' positions are read
  // with contiguous vector loads instead of gathers (3x faster on AVX2); otherwise they are gathered.
  for (; i0 + kChunk <= end; i0 += kChunk) {
    // Sums as arrays, one per component (a group of 6 interleaved floats does not vectorise).
    alignas(64) Real fx[kChunk] = {}, fy[kChunk] = {}, fz[kChunk] = {}, ux[kChunk] = {}, uy[kChunk] = {}, uz[kChunk] = {};
    const int32_t* offsets = g.chunk_offsets + static_cast<int64_t>(i0 / kChunk) * kGridDirections;
    // Direction by direction: contiguous loads of the neighbours where the model's chunk index says
    // the chunk is regular in that direction (lanes without the spring read a valid particle with
    // bit 0: zero contribution), gathers otherwise.
    for (int d = 0; d < kGridDirections; ++d) {
      if (offsets[d] != kIrregularChunk) {
        const int32_t b = i0 + offsets[d];
#pragma omp simd
        for (int32_t k = 0; k < kChunk; ++k) {
          SpringForceSum f{fx[k], fy[k], fz[k], 0, 0, 0};
          if constexpr (kNormals) f.ux = ux[k], f.uy = uy[k], f.uz = uz[k];
          add_grid_spring_to<kDamping, kNormals>(g, s, c.inv_dt, i0 + k, d, b + k, (g.spring_mask[i0 + k] >> d) & 1u, f);
          fx[k] = f.fx, fy[k] = f.fy, fz[k] = f.fz;
          if constexpr (kNormals) ux[k] = f.ux, uy[k] = f.uy, uz[k] = f.uz;
        }
      } else {
#pragma omp simd
        for (int32_t k = 0; k < kChunk; ++k) {
          SpringForceSum f{fx[k], fy[k], fz[k], 0, 0, 0};
          if constexpr (kNormals) f.ux = ux[k], f.uy = uy[k], f.uz = uz[k];
          add_grid_spring<kDamping, kNormals>(g, s, c.inv_dt, i0 + k, d, f);
          fx[k] = f.fx, fy[k] = f.fy, fz[k] = f.fz;
          if constexpr (kNormals) ux[k] = f.ux, uy[k] = f.uy, uz[k] = f.uz;
        }
      }
    }
#pragma omp simd
    for (int32_t k = 0; k < kChunk; ++k) {
      verlet_update(s, c, i0 + k, fx[k], fy[k], fz[k]);
      if constexpr (kNormals) write_normal(ux[k], uy[k], uz[k], nx, ny, nz, i0 + k);
    }
  }
  for (int32_t i = i0; i < end; ++i) {  // the last partial chunk: the kernel as a GPU thread runs it
    const SpringForceSum f = grid_spring_forces<kDamping, kNormals>(g, s, c.inv_dt, i);
    verlet_update(s, c, i, f.fx, f.fy, f.fz);
    if constexpr (kNormals) write_normal(f.ux, f.uy, f.uz, nx, ny, nz, i);
  }
}

template <bool kDamping, bool kNormals>
inline __attribute__((always_inline)) void explicit_range(const ExplicitSpringView& model, const ParticleStateView& state,
                                                          const VerletConstants& constants, Real* nx, Real* ny, Real* nz,
                                                          int32_t begin, int32_t end) {
  const ExplicitSpringView m = model;
  const ParticleStateView s = state;
  const VerletConstants c = constants;
  int32_t i0 = begin;
  // Whole chunks of 32 particles through the sliced layout: slot by slot, SIMD lanes across the
  // chunk's particles, contiguous loads of the entries, gathers of the neighbours' positions. Each
  // particle sums its row in order, as the per-particle loop below does.
  if (m.chunk_start != nullptr) {
    const int32_t chunks = m.count / kExplicitChunk;
    for (; i0 + kExplicitChunk <= end && i0 / kExplicitChunk < chunks; i0 += kExplicitChunk) {
      alignas(64) Real fx[kExplicitChunk] = {}, fy[kExplicitChunk] = {}, fz[kExplicitChunk] = {};
      alignas(64) Real ux[kExplicitChunk] = {}, uy[kExplicitChunk] = {}, uz[kExplicitChunk] = {};
      const int32_t chunk = i0 / kExplicitChunk;
      for (int64_t at = m.chunk_start[chunk]; at < m.chunk_start[chunk + 1]; at += kExplicitChunk) {
#pragma omp simd
        for (int32_t k = 0; k < kExplicitChunk; ++k) {
          const int32_t i = i0 + k;
          const int32_t j = m.ell_neighbour[at + k];
          const Real xi = s.x[i], yi = s.y[i], zi = s.z[i];
          Real dvx = 0, dvy = 0, dvz = 0;
          if constexpr (kDamping) {
            dvx = ((s.x[j] - s.px[j]) - (xi - s.px[i])) * c.inv_dt;
            dvy = ((s.y[j] - s.py[j]) - (yi - s.py[i])) * c.inv_dt;
            dvz = ((s.z[j] - s.pz[j]) - (zi - s.pz[i])) * c.inv_dt;
          }
          SpringForceSum f{fx[k], fy[k], fz[k], 0, 0, 0};
          if constexpr (kNormals) f.ux = ux[k], f.uy = uy[k], f.uz = uz[k];
          add_spring<kDamping, kNormals>(s.x[j] - xi, s.y[j] - yi, s.z[j] - zi, dvx, dvy, dvz, m.ell_stiffness[at + k],
                                         m.ell_rest_length[at + k], m.ell_damping[at + k], m.ell_present[at + k], f);
          fx[k] = f.fx, fy[k] = f.fy, fz[k] = f.fz;
          if constexpr (kNormals) ux[k] = f.ux, uy[k] = f.uy, uz[k] = f.uz;
        }
      }
#pragma omp simd
      for (int32_t k = 0; k < kExplicitChunk; ++k) {
        verlet_update(s, c, i0 + k, fx[k], fy[k], fz[k]);
        if constexpr (kNormals) write_normal(ux[k], uy[k], uz[k], nx, ny, nz, i0 + k);
      }
    }
  }
  // The rest (the last partial chunk): one particle at a time through its CSR row, as a GPU thread.
  for (int32_t i = i0; i < end; ++i) {
    const SpringForceSum f = explicit_spring_forces<kDamping, kNormals>(m, s, c.inv_dt, i);
    verlet_update(s, c, i, f.fx, f.fy, f.fz);
    if constexpr (kNormals) write_normal(f.ux, f.uy, f.uz, nx, ny, nz, i);
  }
}

// Non-template entry points (target_clones does not apply to templates).
#define CTSURG_RANGE(name, view_type, body, damping, normals)                                                  \
  CTSURG_CPU_CLONES void name(const view_type& m, const ParticleStateView& s, const VerletConstants& c, Real* nx, \
                              Real* ny, Real* nz, int32_t begin, int32_t end) {                               \
    body<damping, normals>(m, s, c, nx, ny, nz, begin, end);                                                  \
  }
CTSURG_RANGE(grid_plain, SpringGridView, grid_range, false, false)
CTSURG_RANGE(grid_normals, SpringGridView, grid_range, false, true)
CTSURG_RANGE(grid_damped, SpringGridView, grid_range, true, false)
CTSURG_RANGE(grid_damped_normals, SpringGridView, grid_range, true, true)
CTSURG_RANGE(explicit_plain, ExplicitSpringView, explicit_range, false, false)
CTSURG_RANGE(explicit_normals, ExplicitSpringView, explicit_range, false, true)
CTSURG_RANGE(explicit_damped, ExplicitSpringView, explicit_range, true, false)
CTSURG_RANGE(explicit_damped_normals, ExplicitSpringView, explicit_range, true, true)
#undef CTSURG_RANGE

// Static partition of [0, n) into equal ranges, boundaries on multiples of 64 particles.
template <class Range>
void parallel_ranges(int32_t n, int threads, const Range& range) {
  const int t = thread_count(threads, n);
#pragma omp parallel num_threads(t)
  {
    const int count = omp_get_num_threads(), id = omp_get_thread_num();
    const int64_t blocks = (static_cast<int64_t>(n) + 63) / 64;
    const auto begin = static_cast<int32_t>(std::min<int64_t>(n, blocks * id / count * 64));
    const auto end = static_cast<int32_t>(std::min<int64_t>(n, blocks * (id + 1) / count * 64));
    if (begin < end) range(begin, end);
  }
}

}  // namespace

void grid_step(const SpringGridView& grid, const ParticleStateView& state, const VerletConstants& constants,
               bool spring_damping, Real* nx, Real* ny, Real* nz, int threads) {
  const auto kernel = nx == nullptr ? (spring_damping ? grid_damped : grid_plain)
                                    : (spring_damping ? grid_damped_normals : grid_normals);
  parallel_ranges(state.count, threads,
                  [&](int32_t b, int32_t e) { kernel(grid, state, constants, nx, ny, nz, b, e); });
}

void explicit_step(const ExplicitSpringView& model, const ParticleStateView& state, const VerletConstants& constants,
                   bool spring_damping, Real* nx, Real* ny, Real* nz, int threads) {
  const auto kernel = nx == nullptr ? (spring_damping ? explicit_damped : explicit_plain)
                                    : (spring_damping ? explicit_damped_normals : explicit_normals);
  parallel_ranges(state.count, threads,
                  [&](int32_t b, int32_t e) { kernel(model, state, constants, nx, ny, nz, b, e); });
}

}  // namespace ctsurg::sim::cpu
