// A rigid instrument's contact with a spring model (base/instrument.h): after each step, every free
// particle inside the instrument is projected out of it along the instrument's distance gradient (the
// same position update as the sphere probe's, sphere_tools.h, for any closed shape). As with the probe,
// the previous position is left alone, so the projection also gives the particle the velocity of
// the instrument's surface pushing it (Verlet: v = (x - x_prev) / dt). Fixed particles stay.
//
// Per-particle kernel: base/kernels/instrument_contact_impl.h. Units: LPS mm (the run's frame).
#pragma once

#include "ctsurg/sim/base/instrument.h"
#include "ctsurg/sim/base/particle_state.h"

#include <cstdint>

namespace ctsurg::sim {

// Projects the free particles inside the instrument (`view`: its distance grid at its pose) out of
// it; returns how many moved.
int64_t push_out_of_instrument(ParticleState& state, const InstrumentView& view, int threads = 0);

// The deepest penetration of the free particles into the instrument (mm, >= 0; 0: none inside).
double instrument_penetration(const ParticleState& state, const InstrumentView& view);

}  // namespace ctsurg::sim
