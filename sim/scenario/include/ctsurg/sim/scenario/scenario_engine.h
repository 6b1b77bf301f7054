// A scenario's model as a simulation engine (base/simulation_engine.h): reads the input files the
// model needs (scenario_model.h), moves them into the run's local frame, builds the model with the
// scenario's material, fixes the fixed regions, ties the surface to the model, and makes the engine on
// the scenario's backend:
//
//   spring_grid, explicit_springs   SpringEngine (springs/spring_engine.h); the local origin is the
//                                   whole-millimetre point nearest the grid's centre
//   fem                             FemEngine (fem/fem_engine.h); the local origin is the
//                                   whole-millimetre point nearest the tet mesh's centre
//   vessel                          VesselEngine (vessel/vessel_engine.h) on the centerline's atoms, cpu
//                                   only; the local origin is the whole-millimetre point nearest the
//                                   centerline's centre
//
// Every problem a user can fix is an InputError naming the scenario file and the field: a backend
// that cannot run here ("backend"), a fixed region that selects nothing ("fixed[r]"), an FEM step
// above the critical one ("time.dt_s"), a force tool on a CUDA device (the tool's label).
#pragma once

#include "ctsurg/sim/base/simulation_engine.h"
#include "ctsurg/sim/scenario/scenario.h"

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace ctsurg::sim {

struct ScenarioEngine {
  std::unique_ptr<SimulationEngine> engine;
  std::vector<float> surface_lps_vertices;  // the surface file's vertices (#V x 3 LPS mm); empty: no surface
};

// note receives what the setup and the engine decide (the step, the surface embedding, captures...).
ScenarioEngine make_scenario_engine(const Scenario& scenario, const std::function<void(const std::string&)>& note = {});

}  // namespace ctsurg::sim
