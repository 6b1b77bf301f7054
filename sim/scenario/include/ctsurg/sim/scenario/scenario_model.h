// The model a scenario names, as facts the rest of ctsurg asks for in one place: which of the
// scenario's input files a run reads (the scenario engine opens them, ctsurg-sim --describe lists them
// for the pipeline, the trajectory's provenance hashes them) and how a trajectory labels the model.
//
//   spring_grid                     grid (+ surface)
//   explicit_springs, from grid     grid (+ surface)
//   explicit_springs, from tetmesh  tetmesh and grid (the grid's centre sets the run's local frame)
//                                   (+ surface, embedded in the tets)
//   fem                             tetmesh (+ surface, embedded in the tets); a grid it names is not read
//   vessel                          centerline (the surface is drawn from it: sim/vessel/vessel_skinning.h)
#pragma once

#include "ctsurg/sim/scenario/scenario.h"

#include <string>

namespace ctsurg::sim {

struct ModelInputs {
  bool grid = false;     // scenario.grid
  bool tetmesh = false;  // scenario.tetmesh
  bool surface = false;  // scenario.surface
  bool centerline = false;  // scenario.centerline
};

ModelInputs model_inputs(const Scenario& scenario);

// "spring_grid", "explicit_springs (grid)", "explicit_springs (tetmesh)", "fem neo_hookean (static)", "vessel (rmf)", ...
std::string model_label(const Scenario& scenario);

}  // namespace ctsurg::sim
