#include "ctsurg/sim/springs/spring_cutting.h"

#include "ctsurg/sim/springs/kernels/spring_cutting_impl.h"
#include "spring_cpu_kernels.h"

#include "ctsurg/core/error.h"

#include <cmath>
#include <string>

namespace ctsurg::sim {
namespace {

TriangleView triangle_view(const Triangle& t) {
  TriangleView v{};
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(t.a[a]) || !std::isfinite(t.b[a]) || !std::isfinite(t.c[a]))
      throw InputError("cut", "blade", "triangle corners must be finite");
    v.a[a] = t.a[a], v.b[a] = t.b[a], v.c[a] = t.c[a];
  }
  return v;
}

void check_cut_state(int32_t model_count, const ParticleState& state) {
  if (state.count() != model_count)
    throw InputError("cut", "state", "has " + std::to_string(state.count()) + " particles, the model " + std::to_string(model_count));
}

}  // namespace

int64_t cut_springs_crossing_triangle(SpringGridModel& model, const ParticleState& state, const Triangle& blade, int threads) {
  check_cut_state(model.particle_count(), state);
  const int64_t ends = cpu::cut_grid(model.view(), model.spring_mask.data(), state.x.data(), state.y.data(),
                                     state.z.data(), triangle_view(blade), threads);
  return ends / 2;  // both particles of a cut spring clear their bit
}

int64_t cut_springs_crossing_triangle(ExplicitSpringModel& model, const ParticleState& state, const Triangle& blade,
                                      int threads) {
  check_cut_state(model.particle_count(), state);
  const int64_t cut = cpu::cut_explicit(model.spring_ends.data(), model.alive.data(), model.spring_count(),
                                       state.x.data(), state.y.data(), state.z.data(), triangle_view(blade), threads);
  if (cut > 0) sync_cut_springs(model);
  return cut;
}

}  // namespace ctsurg::sim
