#include "ctsurg/sim/fem/fem_integrator.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/fem/fem_engine.h"
#include "fem_integrators.h"

namespace ctsurg::sim {

FemAdvance FemIntegrator::advance(FemToolHolds&, const std::vector<ToolInput>&, int, std::vector<double>&) {
  throw RuntimeError("fem integrator: the static FEM solver has no time steps (it solves each frame)");
}

FemAdvance FemIntegrator::equilibrium(FemToolHolds&, const std::vector<ToolInput>&, double, bool, std::vector<double>&) {
  throw RuntimeError("fem integrator: the dynamic FEM solver steps in time (it has no equilibrium solve)");
}

std::unique_ptr<FemIntegrator> make_fem_integrator(const FemModel& model, const FemBoundaryConditions& supports,
                                                   const FemEngineOptions& options, Backend backend) {
  switch (options.solver) {
    case FemSolver::dynamic: return make_fem_explicit_integrator(model, supports, options, backend);
    case FemSolver::implicit: return make_fem_implicit_integrator(model, supports, options, backend);
    case FemSolver::static_equilibrium: return make_fem_static_integrator(model, supports, options, backend);
  }
  throw RuntimeError("fem integrator: unknown solver");
}

}  // namespace ctsurg::sim
