// A spring engine on a block of 2 mm liver cells (sim_test_models.h's block_occupancy: cell centres from
// x = 12 mm, y = -18 mm, z = 32 mm) carrying the block's surface with close_cuts on, fixed where the rest
// x <= fixed_below_x_mm, mass damping 30 /s, the liver's density (a cautery counts volume by it), and
// "s.yaml" naming it in messages: the suture's and the cautery's tests.
#pragma once

#include "block_surface.h"
#include "ctsurg/sim/base/fixed_regions.h"
#include "ctsurg/sim/base/material_presets.h"
#include "ctsurg/sim/springs/spring_calibration.h"
#include "ctsurg/sim/springs/spring_engine.h"
#include "sim_test_models.h"

#include <utility>

namespace ctsurg::sim::test {

inline SpringEngine liver_block_engine(int nx, int ny, int nz, double fixed_below_x_mm) {
  const auto occ = block_occupancy(nx, ny, nz, 2.0);
  SpringGridModel model = build_spring_grid_model(occ, calibrated_grid_material(material_preset("liver"), occ.geometry));
  const SurfaceMesh mesh = block_surface(occ);
  ParticleState state = model.make_state();
  fix_particles(state, particles_in_box(model.rest_positions, {{0, -100, -100}, {fixed_below_x_mm, 100, 100}}));
  EmbeddedSurface surface(couple_surface(mesh, model.lattice, model.cells), mesh.triangles);
  surface.set_close_cuts(true);
  EngineOptions o;
  o.mass_damping = 30;
  o.density = material_preset("liver").density;
  o.where = "s.yaml";
  return SpringEngine(std::move(model), std::move(state), std::move(surface), {0, 0, 0}, o);
}

}  // namespace ctsurg::sim::test
