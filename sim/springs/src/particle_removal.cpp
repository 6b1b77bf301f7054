#include "ctsurg/sim/springs/particle_removal.h"

#include "ctsurg/core/error.h"

#include <algorithm>
#include <string>
#include <utility>

namespace ctsurg::sim {
namespace {

void check_removal(int32_t particles, const ParticleState& state, const std::vector<uint8_t>& removed, double density) {
  if (state.count() != particles) {
    throw InputError("cautery", "state", "has " + std::to_string(state.count()) + " particles, the model " + std::to_string(particles));
  }
  if (removed.size() != static_cast<size_t>(particles)) throw InputError("cautery", "removed", "expected one flag per particle");
  if (!(density > 0)) throw InputError("cautery", "density", "must be > 0 g/mm^3 (a particle's volume is its mass over it)");
}

// The present particles inside the sphere, nearest first (lower id on ties).
std::vector<std::pair<double, int32_t>> particles_inside(const ParticleState& state, const std::vector<uint8_t>& removed,
                                                         const Sphere& sphere) {
  std::vector<std::pair<double, int32_t>> inside;
  const double r2 = sphere.radius * sphere.radius;
  for (int32_t i = 0; i < state.count(); ++i) {
    const size_t k = static_cast<size_t>(i);
    if (removed[k] || state.inv_mass[k] == Real(0)) continue;
    const double dx = state.x[k] - sphere.centre[0], dy = state.y[k] - sphere.centre[1], dz = state.z[k] - sphere.centre[2];
    const double d2 = dx * dx + dy * dy + dz * dz;
    if (d2 < r2) inside.emplace_back(d2, i);
  }
  std::sort(inside.begin(), inside.end());
  return inside;
}

// Takes the particles in order while the budget lasts; take(i) drops particle i's springs and returns
// how many it had.
template <typename Take>
RemovalResult remove_in_order(const std::vector<Real>& mass, ParticleState& state, std::vector<uint8_t>& removed,
                              const Sphere& sphere, double density, double* budget_mm3, Take take) {
  RemovalResult r;
  const auto inside = particles_inside(state, removed, sphere);
  size_t k = 0;
  for (; k < inside.size(); ++k) {
    const size_t i = static_cast<size_t>(inside[k].second);
    const double volume = mass[i] / density;
    if (volume > *budget_mm3) break;
    *budget_mm3 -= volume;
    r.volume_mm3 += volume;
    r.springs += take(inside[k].second);
    removed[i] = 1;
    state.inv_mass[i] = 0;
    state.px[i] = state.x[i];
    state.py[i] = state.y[i];
    state.pz[i] = state.z[i];
    r.particles.push_back(inside[k].second);
  }
  r.exhausted = k == inside.size();
  return r;
}

}  // namespace

RemovalResult remove_particles_in_sphere(SpringGridModel& model, ParticleState& state, std::vector<uint8_t>& removed,
                                         const Sphere& sphere, double density, double* budget_mm3) {
  check_removal(model.particle_count(), state, removed, density);
  const size_t n = static_cast<size_t>(model.particle_count());
  return remove_in_order(model.mass, state, removed, sphere, density, budget_mm3, [&](int32_t p) {
    int64_t springs = 0;
    const size_t i = static_cast<size_t>(p);
    for (int d = 0; d < kGridDirections; ++d) {
      if (!(model.spring_mask[i] & (1u << d))) continue;
      model.spring_mask[i] &= ~(1u << d);
      const int32_t q = model.neighbours[static_cast<size_t>(d) * n + i];
      if (q >= 0) model.spring_mask[static_cast<size_t>(q)] &= ~(1u << opposite_direction(d));
      ++springs;
    }
    return springs;
  });
}

RemovalResult remove_particles_in_sphere(ExplicitSpringModel& model, ParticleState& state, std::vector<uint8_t>& removed,
                                         const Sphere& sphere, double density, double* budget_mm3) {
  check_removal(model.particle_count(), state, removed, density);
  return remove_in_order(model.mass, state, removed, sphere, density, budget_mm3, [&](int32_t p) {
    int64_t springs = 0;
    const size_t i = static_cast<size_t>(p);
    for (int32_t e = model.row_offsets[i]; e < model.row_offsets[i + 1]; ++e) {
      springs += cut_explicit_spring(model, model.row_spring[static_cast<size_t>(e)]) ? 1 : 0;
    }
    return springs;
  });
}

}  // namespace ctsurg::sim
