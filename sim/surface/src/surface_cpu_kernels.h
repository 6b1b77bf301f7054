// The CPU launcher of the surface coupling kernel (OpenMP), called by move_surface after its checks.
#pragma once

#include "ctsurg/sim/surface/kernels/surface_coupling_impl.h"

namespace ctsurg::sim::cpu {

void move_surface(const SurfaceCouplingView& view, int threads);

}  // namespace ctsurg::sim::cpu
