// The scenario's `time:` section: how long, the step (or auto: a fraction of the critical step) and
// the stability guard's halvings. Needs the tools (none may start after the run).
#include "scenario_sections.h"

#include "ctsurg/core/error.h"

namespace ctsurg::sim {

void parse_time_section(const YamlField& top, Scenario& s) {
  const YamlField t = top.child("time");
  t.only({"duration_s", "dt_s", "safety_factor", "max_step_halvings", "integrator"});
  // Bounds of a rehearsal, not of physics: at most a day of simulated time, steps of at least a
  // nanosecond (the explicit models' critical steps are microseconds to milliseconds). How long a
  // run within them takes on this machine is estimated when it starts (ctsurg-sim --force).
  s.duration_s = t.child("duration_s").positive();
  if (s.duration_s > kMaxDurationS) {
    t.child("duration_s").fail("must be at most " + YamlField::num(kMaxDurationS) + " s (a day of simulated time)");
  }
  if (t.has("dt_s")) {
    const YamlField dt = t.child("dt_s");
    if (dt.is_scalar() && dt.text() == "auto") {
      s.dt_s = 0;
    } else {
      s.dt_s = dt.positive();
      if (s.dt_s > s.duration_s) dt.fail("the step is longer than the run");
      if (s.dt_s < kMinStepS) dt.fail("must be at least " + YamlField::num(kMinStepS) + " s");
    }
  }
  if (t.has("safety_factor")) {
    s.safety_factor = t.child("safety_factor").positive();
    if (s.safety_factor > 1) t.child("safety_factor").fail("must be in (0, 1]");
  }
  if (t.has("integrator")) {
    // fem implicit: backward Euler (damps every mode by the step) or the implicit midpoint rule (keeps
    // the motion; the damping is the material's Rayleigh constants), fem/fem_implicit_dynamics.h.
    const YamlField i = t.child("integrator");
    if (s.model != ModelKind::fem || s.fem_solver != FemSolver::implicit) i.fail("only for kind: fem with solver: implicit");
    s.implicit_scheme = i.one_of({"backward_euler", "midpoint"}) == "midpoint" ? FemImplicitScheme::midpoint : FemImplicitScheme::backward_euler;
  }
  if (t.has("max_step_halvings")) s.max_step_halvings = static_cast<int>(t.child("max_step_halvings").integer(0, 10));
  for (const auto& tool : s.tools) {
    if (tool.start_s >= s.duration_s) {
      throw InputError(t.file(), tool.label + ".start_s", "the tool starts after the run ends (duration_s " +
                                                          YamlField::num(s.duration_s) + ")");
    }
  }
}

}  // namespace ctsurg::sim
