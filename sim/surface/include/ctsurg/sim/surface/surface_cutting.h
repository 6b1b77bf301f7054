// Cutting the rendered surface with the same blade that cuts the springs, so that an incision opens
// on screen: every surface triangle with an edge crossing the blade is removed, and every vertex stops
// following the particles on the far side of the blade (its coupling slots whose segment vertex ->
// particle crosses the blade are dropped and the remaining weights renormalised). As the cut springs
// let the two sides separate, each side's vertices go with their own side and the gap widens. The
// walls of the incision are not closed (the renderer lights the inside of the surface two-sided).
//
// Positions are the current ones (LPS mm): the surface's vertices as move_surface() wrote them and the
// particles' x, y, z. Per-triangle and per-vertex kernels: src/surface_cutting_impl.h.
#pragma once

#include "ctsurg/sim/base/particle_state.h"
#include "ctsurg/sim/base/tool_shapes.h"
#include "ctsurg/sim/surface/surface_coupling.h"

#include <cstdint>
#include <vector>

namespace ctsurg::sim {

struct SurfaceCutResult {
  int64_t triangles_removed = 0;
  int64_t slots_detached = 0;  // coupling slots dropped
};

// triangles: #F x 3 (kept in order, the crossed ones removed); vertices: #V x 3 current positions.
// A vertex whose every slot lies across the blade keeps its slots (nothing to follow otherwise).
// Only the first half: removes the triangles with an edge crossing the blade (kept in order); returns how
// many. For a surface tied to elements that a cut keeps whole (the FEM's tets: fem/fem_cutting.h).
int64_t remove_crossed_triangles(std::vector<uint32_t>& triangles, const std::vector<float>& vertices, const Triangle& blade);

SurfaceCutResult cut_surface(std::vector<uint32_t>& triangles, SurfaceCoupling& coupling, const std::vector<float>& vertices,
                             const ParticleState& state, const Triangle& blade);

}  // namespace ctsurg::sim
