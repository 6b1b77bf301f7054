// Time-step sweep (issue 9): for each model, the largest stable step found by bisection, against the
// step the library predicts (stability.h: min_i 2 sqrt(m_i / K_i) for springs; fem_explicit_dynamics.h:
// min_e h_e / c for FEM). A step is stable when an undamped run of `steps` steps from a randomly
// perturbed rest state (0.01 mm), one face clamped, keeps finite positions, never trips the guard and
// ends with total energy within 2x of its start. Prints a markdown table (docs/accuracy.md).
//
//   stability_sweep [steps]     (default 3000)
//
// FEM: FemExplicitDynamics refuses a dt above its critical step (InputError), so its bisection runs in
// (0, 1] x dt_crit and a ratio of 1.00 means "stable at the predicted step itself".
#include "ctsurg/core/error.h"

#include <cstdio>
#include <cstdlib>
#include "ctsurg/core/tet_mesh_file.h"
#include "ctsurg/core/volume.h"
#include "ctsurg/sim/base/material_presets.h"
#include "ctsurg/sim/fem/fem_box_mesh.h"
#include "ctsurg/sim/fem/fem_explicit_dynamics.h"
#include "ctsurg/sim/fem/fem_model.h"
#include "ctsurg/sim/springs/explicit_spring_model.h"
#include "ctsurg/sim/springs/spring_calibration.h"
#include "ctsurg/sim/springs/spring_grid_model.h"
#include "ctsurg/sim/springs/spring_mass_step.h"
#include "ctsurg/sim/springs/stability.h"

#include <cmath>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

using namespace ctsurg;
using namespace ctsurg::sim;

namespace {

int g_steps = 3000;

uint64_t g_seed = 1;
double next_random() {
  g_seed = g_seed * 6364136223846793005ull + 1442695040888963407ull;
  return static_cast<double>(g_seed >> 11) / static_cast<double>(1ull << 53) * 2.0 - 1.0;
}

// Undamped spring run at dt: stable?
template <class Model>
bool springs_stable(const Model& model, double dt, const std::vector<int32_t>& fixed) {
  ParticleState s = model.make_state();
  g_seed = 7;
  for (int32_t i = 0; i < s.count(); ++i) {
    s.x[i] += Real(0.01 * next_random()), s.y[i] += Real(0.01 * next_random()), s.z[i] += Real(0.01 * next_random());
    s.px[i] = s.x[i], s.py[i] = s.y[i], s.pz[i] = s.z[i];
  }
  for (const int32_t i : fixed) s.set_fixed(i, true);
  StepParameters p;
  p.dt = dt;
  StabilityGuard guard = make_stability_guard(model, dt);
  const double e0 = spring_energy(model, s);
  for (int n = 1; n <= g_steps; ++n) {
    step(model, s, p);
    if (n % 50 == 0 && !guard.check(s, n * dt).stable) return false;
  }
  const double e = spring_energy(model, s) + kinetic_energy(s, dt);
  return std::isfinite(e) && e < 2 * e0;
}

bool fem_stable(const FemModel& model, double dt, const std::vector<int32_t>& fixed) {
  try {
    FemDynamicsOptions o;
    o.dt = dt;
    FemExplicitDynamics d(model, o);
    d.set_fixed_nodes(fixed);
    std::vector<double> f(model.nodes.size());
    g_seed = 7;
    // A random load of +-100 uN per node for 10 steps (displacements ~1e-3 mm, far above float rounding
    // of the positions), then free vibration.
    for (auto& x : f) x = 1e2 * next_random();
    d.set_external_forces(f);
    d.step(10);
    d.set_external_forces({});
    const double e0 = d.kinetic_energy() + d.strain_energy();
    d.step(g_steps);
    const double e = d.kinetic_energy() + d.strain_energy();
    if (std::getenv("SWEEP_DEBUG")) std::fprintf(stderr, "fem dt %g: e0 %g e %g\n", dt, e0, e);
    return std::isfinite(e) && e < 2 * e0;
  } catch (const RuntimeError& err) {
    if (std::getenv("SWEEP_DEBUG")) std::fprintf(stderr, "fem dt %g: %s\n", dt, err.what());
    return false;
  }
}

// Largest stable ratio r in [lo, hi] (dt = r * predicted) by bisection, assuming lo is stable.
double bisect(const std::function<bool(double)>& stable, double lo, double hi) {
  if (stable(hi)) return hi;
  if (!stable(lo)) return 0;
  for (int i = 0; i < 12; ++i) {
    const double mid = 0.5 * (lo + hi);
    (stable(mid) ? lo : hi) = mid;
  }
  return lo;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1) g_steps = std::stoi(argv[1]);
  const Material tissue{"custom", 30000, 0.45, 1.06e-3, ""};
  std::printf("| model | case | predicted dt_crit (s) | largest stable dt (s) | ratio |\n|---|---|---:|---:|---:|\n");
  auto row = [](const char* model, const char* c, double predicted, double ratio) {
    std::printf("| %s | %s | %.3g | %.3g | %.2f |\n", model, c, predicted, ratio * predicted, ratio);
    std::fflush(stdout);
  };
  // Spring grid: a 12 x 6 x 6 block of 2 mm cells, k = 0.4 E h; x = 0 face clamped.
  ImageGeometry g;
  g.dims = {14, 8, 8};
  g.spacing = Eigen::Vector3d(2, 2, 2);
  Volume<uint8_t> occ(g, 0);
  for (int k = 1; k <= 6; ++k)
    for (int j = 1; j <= 6; ++j)
      for (int i = 1; i <= 12; ++i) occ(i, j, k) = 1;
  const SpringGridModel grid = build_spring_grid_model(occ, calibrated_grid_material(tissue, g));
  std::vector<int32_t> gfixed;
  for (int32_t i = 0; i < grid.particle_count(); ++i)
    if (grid.rest_positions[3 * i] < 2.5) gfixed.push_back(i);
  {
    const double c = critical_time_step(grid).critical;
    row("spring grid", "block 12x6x6, 2 mm", c, bisect([&](double r) { return springs_stable(grid, r * c, gfixed); }, 0.1, 4));
  }
  // The same springs, explicit; and with the x < 12 mm half 1000x stiffer.
  const ExplicitSpringModel ex = explicit_model_from_grid(grid);
  {
    const double c = critical_time_step(ex).critical;
    row("explicit springs", "grid springs", c, bisect([&](double r) { return springs_stable(ex, r * c, gfixed); }, 0.1, 4));
    std::vector<Spring> springs;
    for (int32_t s = 0; s < ex.spring_count(); ++s) {
      const int32_t i = ex.spring_ends[2 * s], j = ex.spring_ends[2 * s + 1];
      const bool stiff = ex.rest_positions[3 * i] < 12 && ex.rest_positions[3 * j] < 12;
      springs.push_back({i, j, ex.stiffness[s] * (stiff ? 1000.0 : 1.0), ex.rest_length[s], 0.0});
    }
    const ExplicitSpringModel ratio = build_explicit_spring_model(ex.rest_positions, ex.mass, springs);
    const double c2 = critical_time_step(ratio).critical;
    row("explicit springs", "stiffness ratio 1000", c2, bisect([&](double r) { return springs_stable(ratio, r * c2, gfixed); }, 0.1, 4));
  }
  // Tet meshes: 6 x 3 x 3 cells of 4 mm (Kuhn), regular and with the top layer flattened to 5 %.
  for (const bool flat : {false, true}) {
    FemBoxMesh b = fem_box_mesh({6, 3, 3}, {24, 12, 12});
    if (flat)
      for (size_t n = 0; n < b.nodes.size() / 3; ++n)
        if (b.nodes[3 * n + 2] > 11.999) b.nodes[3 * n + 2] = 8 + 0.2;
    const char* name = flat ? "box 6x3x3, top layer flattened to 5 %" : "box 6x3x3, 4 mm Kuhn tets";
    std::vector<int32_t> fixed;
    for (size_t n = 0; n < b.nodes.size() / 3; ++n)
      if (b.nodes[3 * n] < 0.5) fixed.push_back(static_cast<int32_t>(n));
    TetMesh tm;
    tm.nodes = b.nodes;
    tm.tets = b.tets;
    tm.tet_labels.assign(b.tets.size() / 4, 1);
    const ExplicitSpringModel ts = calibrated_tet_spring_model(tm, tissue);
    const double c = critical_time_step(ts).critical;
    row("explicit springs (tet edges)", name, c, bisect([&](double r) { return springs_stable(ts, r * c, fixed); }, 0.1, 4));
    for (const FemLaw law : {FemLaw::linear, FemLaw::neo_hookean}) {
      FemMaterial m;
      m.law = law;
      m.youngs_modulus = tissue.youngs_modulus_pa;
      m.poisson_ratio = tissue.poisson_ratio;
      m.density = tissue.density;
      const FemModel model = build_fem_model(b.nodes, b.tets, m);
      const double fc = fem_critical_time_step(model).critical;
      row(law == FemLaw::linear ? "FEM explicit, linear" : "FEM explicit, Neo-Hookean", name, fc,
          bisect([&](double r) { return fem_stable(model, r * fc, fixed); }, 0.05, 1.0));
    }
  }
  return 0;
}
