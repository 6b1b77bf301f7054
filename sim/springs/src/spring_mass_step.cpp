#include "ctsurg/sim/springs/spring_mass_step.h"

#include "spring_cpu_kernels.h"
#include "verlet_constants.h"

#include "ctsurg/core/error.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace ctsurg::sim {
namespace {

VerletConstants check_parameters(const StepParameters& p, int32_t model_count, const ParticleState& state) {
  const VerletConstants c = verlet_constants(p, "step");
  if (p.threads < 0) throw InputError("step", "threads", "must be >= 0");
  if (state.count() != model_count)
    throw InputError("step", "state", "has " + std::to_string(state.count()) + " particles, the model " +
                                          std::to_string(model_count));
  return c;
}

void size_normals(ParticleNormals* normals, int32_t n) {
  if (normals == nullptr) return;
  normals->x.resize(n), normals->y.resize(n), normals->z.resize(n);
}

}  // namespace

void step(const SpringGridModel& model, ParticleState& state, const StepParameters& parameters, ParticleNormals* normals) {
  const VerletConstants c = check_parameters(parameters, model.particle_count(), state);
  size_normals(normals, state.count());
  const bool damping = std::any_of(model.damping.begin(), model.damping.end(), [](Real v) { return v > 0; });
  cpu::grid_step(model.view(), state.view(), c, damping, normals ? normals->x.data() : nullptr,
                 normals ? normals->y.data() : nullptr, normals ? normals->z.data() : nullptr, parameters.threads);
  state.advance();
}

void step(const ExplicitSpringModel& model, ParticleState& state, const StepParameters& parameters, ParticleNormals* normals) {
  const VerletConstants c = check_parameters(parameters, model.particle_count(), state);
  size_normals(normals, state.count());
  const bool damping = model.spring_damping;
  cpu::explicit_step(model.view(), state.view(), c, damping, normals ? normals->x.data() : nullptr,
                     normals ? normals->y.data() : nullptr, normals ? normals->z.data() : nullptr, parameters.threads);
  state.advance();
}

}  // namespace ctsurg::sim
