// The CPU launchers of the sim kernels (OpenMP), called by the dispatchers after their checks.
#pragma once

#include "verlet_step_impl.h"

#include <omp.h>

#include <algorithm>
#include <cstdint>

#include "ctsurg/sim/explicit_spring_model.h"
#include "ctsurg/sim/particle_state.h"
#include "ctsurg/sim/spring_grid_model.h"

namespace ctsurg::sim {
struct SurfaceCouplingView;
struct TriangleView;
struct SphereView;
}

namespace ctsurg::sim::cpu {

// OpenMP threads for a kernel over `work` items: `requested` when > 0, else one thread per 8,192 items
// up to OpenMP's default (a small kernel is shorter than waking a thread team, and much shorter when
// the cores are busy with other work).
inline int thread_count(int requested, int64_t work) {
  if (requested > 0) return requested;
  return static_cast<int>(std::clamp<int64_t>(work / 8192, 1, omp_get_max_threads()));
}

// normals: three #P arrays, or all null.
void grid_step(const SpringGridView& grid, const ParticleStateView& state, const VerletConstants& constants,
               bool spring_damping, Real* nx, Real* ny, Real* nz, int threads);
void explicit_step(const ExplicitSpringView& model, const ParticleStateView& state, const VerletConstants& constants,
                   bool spring_damping, Real* nx, Real* ny, Real* nz, int threads);

void move_surface(const SurfaceCouplingView& view, int threads);

// Cutting (in place); return the number of spring ends (grid) or springs (explicit) cleared.
int64_t cut_grid(const SpringGridView& grid, uint32_t* spring_mask, const Real* x, const Real* y, const Real* z,
                 const TriangleView& blade, int threads);
int64_t cut_explicit(const int32_t* ends, uint8_t* alive, int32_t springs, const Real* x, const Real* y, const Real* z,
                     const TriangleView& blade, int threads);

// Spherical tools.
void inside_sphere(const Real* x, const Real* y, const Real* z, int32_t count, const SphereView& tool, uint8_t* inside,
                   int threads);
int64_t probe(Real* x, Real* y, Real* z, const Real* inv_mass, int32_t count, const SphereView& tool, int threads);
void place_grabbed(Real* x, Real* y, Real* z, const int32_t* ids, const Real* offsets, int64_t count,
                   const SphereView& tool, int threads);

}  // namespace ctsurg::sim::cpu
