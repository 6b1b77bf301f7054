// The CPU launchers of the spring kernels (OpenMP), called by the dispatchers after their checks.
#pragma once

#include "ctsurg/sim/base/parallel.h"
#include "ctsurg/sim/springs/kernels/verlet_step_impl.h"

#include <cstdint>

#include "ctsurg/sim/base/particle_state.h"
#include "ctsurg/sim/springs/explicit_spring_model.h"
#include "ctsurg/sim/springs/spring_grid_model.h"

namespace ctsurg::sim {
struct TriangleView;
struct SphereView;
struct InstrumentView;
}

namespace ctsurg::sim::cpu {

// normals: three #P arrays, or all null.
void grid_step(const SpringGridView& grid, const ParticleStateView& state, const VerletConstants& constants,
               bool spring_damping, Real* nx, Real* ny, Real* nz, int threads);
void explicit_step(const ExplicitSpringView& model, const ParticleStateView& state, const VerletConstants& constants,
                   bool spring_damping, Real* nx, Real* ny, Real* nz, int threads);

// Cutting (in place); return the number of spring ends (grid) or springs (explicit) cleared.
int64_t cut_grid(const SpringGridView& grid, uint32_t* spring_mask, const Real* x, const Real* y, const Real* z,
                 const TriangleView& blade, int threads);
int64_t cut_explicit(const int32_t* ends, uint8_t* alive, int32_t springs, const Real* x, const Real* y, const Real* z,
                     const TriangleView& blade, int threads);

// Spherical tools.
void grabbable(const Real* x, const Real* y, const Real* z, const Real* inv_mass, int32_t count, const SphereView& tool,
               uint8_t* inside, int threads);
int64_t probe(Real* x, Real* y, Real* z, const Real* inv_mass, int32_t count, const SphereView& tool, int threads);
void place_grabbed(Real* x, Real* y, Real* z, const int32_t* ids, const Real* offsets, int64_t count,
                   const SphereView& tool, int threads);

// Instruments: projects the free particles out; returns how many moved.
int64_t push_out(Real* x, Real* y, Real* z, const Real* inv_mass, int32_t count, const InstrumentView& view, int threads);

}  // namespace ctsurg::sim::cpu
