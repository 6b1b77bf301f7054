#include "ctsurg/sim/base/particle_state.h"

#include "ctsurg/core/error.h"

#include <cmath>
#include <string>

namespace ctsurg::sim {

ParticleState::ParticleState(const std::vector<Real>& positions, const std::vector<Real>& masses) {
  if (positions.size() != 3 * masses.size())
    throw InputError("particle state", "positions",
                     "expected 3 x " + std::to_string(masses.size()) + " values, got " + std::to_string(positions.size()));
  const std::size_t n = masses.size();
  x.resize(n), y.resize(n), z.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (!(std::isfinite(masses[i]) && masses[i] > 0))
      throw InputError("particle state", "mass", "particle " + std::to_string(i) + " has mass " +
                                                     std::to_string(masses[i]) + " g; must be finite and > 0");
    x[i] = positions[3 * i], y[i] = positions[3 * i + 1], z[i] = positions[3 * i + 2];
  }
  px = x, py = y, pz = z;
  nx = x, ny = y, nz = z;
  mass = masses;
  inv_mass.resize(n);
  for (std::size_t i = 0; i < n; ++i) inv_mass[i] = Real(1) / mass[i];
}

ParticleStateView ParticleState::view() {
  return {x.data(), y.data(), z.data(), px.data(), py.data(), pz.data(),
          nx.data(), ny.data(), nz.data(), inv_mass.data(), count()};
}

void ParticleState::advance() {
  px.swap(x), py.swap(y), pz.swap(z);  // previous <- current (the old previous is now in x)
  x.swap(nx), y.swap(ny), z.swap(nz);  // current <- next; next <- old previous (scratch)
}

void ParticleState::set_velocity(int32_t i, double vx, double vy, double vz, double dt) {
  px[i] = static_cast<Real>(x[i] - vx * dt);
  py[i] = static_cast<Real>(y[i] - vy * dt);
  pz[i] = static_cast<Real>(z[i] - vz * dt);
}

void ParticleState::set_fixed(int32_t i, bool fixed) { inv_mass[i] = fixed ? Real(0) : Real(1) / mass[i]; }

}  // namespace ctsurg::sim
