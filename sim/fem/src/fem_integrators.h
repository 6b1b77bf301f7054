// The FEM integrators (fem_integrator.h), one per file, made by make_fem_integrator.
#pragma once

#include "ctsurg/sim/fem/fem_integrator.h"

#include <memory>

namespace ctsurg::sim {

std::unique_ptr<FemIntegrator> make_fem_explicit_integrator(const FemModel& model, const FemBoundaryConditions& supports,
                                                            const FemEngineOptions& options, Backend backend);
std::unique_ptr<FemIntegrator> make_fem_implicit_integrator(const FemModel& model, const FemBoundaryConditions& supports,
                                                            const FemEngineOptions& options, Backend backend);
std::unique_ptr<FemIntegrator> make_fem_static_integrator(const FemModel& model, const FemBoundaryConditions& supports,
                                                          const FemEngineOptions& options, Backend backend);

}  // namespace ctsurg::sim
