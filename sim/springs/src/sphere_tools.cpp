#include "ctsurg/sim/springs/sphere_tools.h"

#include "ctsurg/sim/springs/kernels/sphere_tools_impl.h"
#include "spring_cpu_kernels.h"

#include "ctsurg/core/error.h"

#include <cmath>
#include <string>

namespace ctsurg::sim {
namespace {

SphereView sphere_tool_view(const std::array<double, 3>& centre, double radius, const char* where) {
  for (double c : centre)
    if (!std::isfinite(c)) throw InputError(where, "centre", "must be finite");
  if (!(std::isfinite(radius) && radius > 0)) throw InputError(where, "radius", "must be finite and > 0, got " + std::to_string(radius));
  return {static_cast<Real>(centre[0]), static_cast<Real>(centre[1]), static_cast<Real>(centre[2]), static_cast<Real>(radius)};
}

}  // namespace

Grab grab_particles_in_sphere(const ParticleState& state, const Sphere& tool, int threads) {
  const SphereView s = sphere_tool_view(tool.centre, tool.radius, "grab");
  std::vector<uint8_t> inside(static_cast<std::size_t>(state.count()));
  cpu::grabbable(state.x.data(), state.y.data(), state.z.data(), state.inv_mass.data(), state.count(), s, inside.data(),
                 threads);
  Grab grab;  // compaction in id order: deterministic
  for (int32_t i = 0; i < state.count(); ++i) {
    if (!inside[i]) continue;
    grab.particles.push_back(i);
    grab.offsets.push_back(state.x[i] - s.cx);
    grab.offsets.push_back(state.y[i] - s.cy);
    grab.offsets.push_back(state.z[i] - s.cz);
  }
  return grab;
}

void apply_grab(ParticleState& state, const Grab& grab, const std::array<double, 3>& centre, int threads) {
  if (grab.offsets.size() != 3 * grab.particles.size()) throw InputError("grab", "offsets", "expected 3 per grabbed particle");
  for (int32_t p : grab.particles)
    if (p < 0 || p >= state.count()) throw InputError("grab", "particles", "id " + std::to_string(p) + " out of range");
  const SphereView s = sphere_tool_view(centre, 1.0, "grab");
  cpu::place_grabbed(state.x.data(), state.y.data(), state.z.data(), grab.particles.data(), grab.offsets.data(),
                     static_cast<int64_t>(grab.particles.size()), s, threads);
}

int64_t probe_sphere(ParticleState& state, const Sphere& tool, int threads) {
  const SphereView s = sphere_tool_view(tool.centre, tool.radius, "probe");
  return cpu::probe(state.x.data(), state.y.data(), state.z.data(), state.inv_mass.data(), state.count(), s, threads);
}

}  // namespace ctsurg::sim
