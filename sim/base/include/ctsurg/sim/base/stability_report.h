// A verdict on a run's stability: what a spring model's guard (springs/stability.h) or an FEM step's
// guard (fem/fem_explicit_dynamics.h) found, as a simulation engine reports it (simulation_engine.h).
#pragma once

#include <cstdint>
#include <string>

namespace ctsurg::sim {

struct StabilityReport {
  bool stable = true;
  double time = 0;            // s, of the check
  int32_t particle = -1;      // the first offending particle or node (lowest id), or -1
  std::string message;        // empty when stable: time, particle, its rest position, the cause,
                              // and a suggested step
};

}  // namespace ctsurg::sim
