// The Verlet step's constants from its parameters (spring_mass_step.h), checked once: the CPU step
// (spring_mass_step.cpp) and the device step (device_simulation.cpp) take the same parameters and
// refuse the same values with the same messages.
#pragma once

#include "ctsurg/sim/springs/kernels/verlet_step_impl.h"
#include "ctsurg/sim/springs/spring_mass_step.h"

namespace ctsurg::sim {

// Throws InputError(where, "dt" | "damping" | "gravity", ...) unless dt is finite and > 0, damping is
// in [0, 1) and gravity is finite.
VerletConstants verlet_constants(const StepParameters& parameters, const char* where);

}  // namespace ctsurg::sim
