#include "ctsurg/sim/springs/instrument_contact.h"

#include "ctsurg/sim/base/kernels/instrument_contact_impl.h"
#include "spring_cpu_kernels.h"


#include <algorithm>

namespace ctsurg::sim {

int64_t push_out_of_instrument(ParticleState& state, const InstrumentView& view, int threads) {
  check_instrument_view(view, "instrument", "distance");
  return cpu::push_out(state.x.data(), state.y.data(), state.z.data(), state.inv_mass.data(), state.count(), view, threads);
}

double instrument_penetration(const ParticleState& state, const InstrumentView& view) {
  double deepest = 0;
  for (int32_t i = 0; i < state.count(); ++i) {
    const size_t k = static_cast<size_t>(i);
    if (state.inv_mass[k] == Real(0)) continue;
    deepest = std::max(deepest, -instrument_signed_distance(view, state.x[k], state.y[k], state.z[k]));
  }
  return deepest;
}

}  // namespace ctsurg::sim
