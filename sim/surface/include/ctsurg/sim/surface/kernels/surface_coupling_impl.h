// Per-vertex surface coupling kernel (see surface_coupling.h): the vertex's rest position plus the
// weighted displacement of the particles it follows.
#pragma once

#include "ctsurg/sim/base/kernels/kernel_support.h"

#include <cstdint>

namespace ctsurg::sim {

struct SurfaceCouplingView {
  const int32_t* particles;    // #V x 8, -1 = none
  const Real* weights;         // #V x 8
  const Real* rest_vertices;   // #V x 3 LPS mm
  const Real* x;               // #P current positions, LPS mm
  const Real* y;
  const Real* z;
  const Real* rest_positions;  // #P x 3 LPS mm
  float* vertices;             // #V x 3 output, LPS mm
  int64_t count;               // #V
};

CTSURG_HD inline void move_vertex(const SurfaceCouplingView& v, int64_t i) {
  Real ux = 0, uy = 0, uz = 0;
  CTSURG_UNROLL
  for (int c = 0; c < 8; ++c) {
    const int32_t p = v.particles[8 * i + c];
    if (p < 0) continue;
    const Real w = v.weights[8 * i + c];
    ux += w * (v.x[p] - v.rest_positions[3 * p]);
    uy += w * (v.y[p] - v.rest_positions[3 * p + 1]);
    uz += w * (v.z[p] - v.rest_positions[3 * p + 2]);
  }
  v.vertices[3 * i] = v.rest_vertices[3 * i] + ux;
  v.vertices[3 * i + 1] = v.rest_vertices[3 * i + 1] + uy;
  v.vertices[3 * i + 2] = v.rest_vertices[3 * i + 2] + uz;
}

}  // namespace ctsurg::sim
