#include "verlet_constants.h"

#include "ctsurg/core/error.h"

#include <cmath>
#include <string>

namespace ctsurg::sim {

VerletConstants verlet_constants(const StepParameters& p, const char* where) {
  if (!(std::isfinite(p.dt) && p.dt > 0)) throw InputError(where, "dt", "must be finite and > 0, got " + std::to_string(p.dt));
  if (!(p.damping >= 0 && p.damping < 1))
    throw InputError(where, "damping", "must be in [0, 1), got " + std::to_string(p.damping));
  for (double g : p.gravity)
    if (!std::isfinite(g)) throw InputError(where, "gravity", "must be finite");
  return {static_cast<Real>(p.dt * p.dt), static_cast<Real>(1.0 / p.dt), static_cast<Real>(1.0 - p.damping),
          static_cast<Real>(p.gravity[0]), static_cast<Real>(p.gravity[1]), static_cast<Real>(p.gravity[2])};
}

}  // namespace ctsurg::sim
