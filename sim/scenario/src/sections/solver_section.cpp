// The scenario's `solver:` section (kind: fem, solver: static or implicit): the Newton solves'
// settings and the local region around the tools (fem/fem_local_region.h); and the tools' own local
// region radii, which need it. Needs the tools.
#include "scenario_sections.h"

#include "ctsurg/core/error.h"

namespace ctsurg::sim {
namespace {

SolverSpec solver_of(const YamlField& f) {
  f.only({"linear", "nonlinear", "tolerance_mm", "max_newton_iterations", "max_cg_iterations", "local_region"});
  SolverSpec s;
  if (f.has("linear")) {
    const std::string kind = f.child("linear").one_of({"auto", "direct", "iterative"});
    s.linear = kind == "direct" ? FemLinearSolve::direct : kind == "iterative" ? FemLinearSolve::iterative : FemLinearSolve::automatic;
  }
  if (f.has("nonlinear")) {
    const std::string kind = f.child("nonlinear").one_of({"newton", "quasi_newton"});
    s.nonlinear = kind == "quasi_newton" ? FemNonlinearSolve::quasi_newton : FemNonlinearSolve::newton;
  }
  if (f.has("tolerance_mm")) {
    s.tolerance_mm = f.child("tolerance_mm").positive();
    if (s.tolerance_mm > 10) f.child("tolerance_mm").fail("must be <= 10 mm (a budget, not a displacement)");
  }
  if (f.has("max_newton_iterations")) s.max_newton_iterations = static_cast<int>(f.child("max_newton_iterations").integer(1, 1000));
  if (f.has("max_cg_iterations")) s.max_cg_iterations = static_cast<int>(f.child("max_cg_iterations").integer(0, 100000000));
  if (f.has("local_region")) {
    const YamlField r = f.child("local_region");
    r.only({"radius_mm", "balance_iterations"});
    s.local_region_mm = r.child("radius_mm").positive();
    if (r.has("balance_iterations")) s.local_region_balance = static_cast<int>(r.child("balance_iterations").integer(0, 100));
  }
  return s;
}

}  // namespace

void parse_solver_section(const YamlField& top, Scenario& s) {
  if (top.has("solver")) {
    if (s.model != ModelKind::fem || s.fem_solver == FemSolver::dynamic)
      top.child("solver").fail("only for kind: fem with solver: static or implicit (the Newton solves' settings)");
    s.solver = solver_of(top.child("solver"));
    if (s.solver.local_region_mm > 0) {
      // The local region (fem/fem_local_region.h) couples quasi-static solves on linear tets around the tools.
      const YamlField r = top.child("solver").child("local_region");
      if (s.fem_solver != FemSolver::static_equilibrium) r.fail("only with solver: static (the region couples quasi-static solves)");
      if (s.fem_order != 1) r.fail("needs linear (4-node) tets (elements: linear)");
      bool acts = false;
      for (const ToolAction& a : s.tools) acts = acts || a.acts() == ToolPrimitive::hold || a.acts() == ToolPrimitive::load;
      if (!acts) r.fail("needs a grab or force tool: the region grows around the nodes the tools hold or load");
      for (const ToolAction& a : s.tools)
        if (a.grip == HoldGrip::volume) r.fail(a.label + " has grip: volume; the region's solve holds node sets (use grip: nodes)");
    }
  }
  // A tool's own local region radius needs the FEM local region.
  for (size_t i = 0; i < s.tools.size(); ++i) {
    if (s.tools[i].local_region_mm > 0 && !(s.solver.local_region_mm > 0)) {
      const YamlField item = top.child("tools").items()[i];
      item.child(item.has("grab") ? "grab" : item.has("clamp") ? "clamp" : "force")
          .child("local_region_mm")
          .fail("a tool's own local region radius needs solver: {local_region: {radius_mm: R}} (kind: fem, solver: static)");
    }
  }
}

}  // namespace ctsurg::sim
