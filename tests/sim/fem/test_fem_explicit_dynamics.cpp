// Tests of sim/fem_explicit_dynamics.h: critical step, free fall, a damped run settling to the static
// solution, inversion -> RuntimeError without NaN, thread-count determinism, sphere contact.
#include "ctsurg/sim/fem/fem_explicit_dynamics.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/fem/fem_box_mesh.h"
#include "ctsurg/sim/fem/fem_forces.h"
#include "ctsurg/sim/fem/fem_static_solver.h"
#include "fem_test_models.h"
#include "instrument_test_shapes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

namespace ctsurg::sim {
namespace {

FemModel beam(std::array<int, 3> cells = {6, 2, 2}, std::array<double, 3> size = {12, 4, 4}) {
  return test::fem_box_model(FemLaw::neo_hookean, cells, size, 3e4, 0.3);
}

using test::nodes_where;

// Two materials: the critical step is the smallest h_e / c_e, so the stiffer material (faster waves)
// sets it on a uniform mesh, as if it filled the whole model.
TEST(FemExplicitDynamics, CriticalStepOfSeveralMaterialsIsTheirSmallest) {
  const FemModel soft = beam();
  FemMaterial stiff = soft.materials[0];
  stiff.youngs_modulus *= 4;
  std::vector<int32_t> ids(static_cast<size_t>(soft.tet_count()));
  for (size_t e = 0; e < ids.size(); ++e) ids[e] = e % 3 == 0 ? 1 : 0;
  const FemModel mixed = build_fem_model(soft.nodes, soft.tets, {soft.materials[0], stiff}, ids);
  const FemModel all_stiff = build_fem_model(soft.nodes, soft.tets, stiff);
  const auto cm = fem_critical_time_step(mixed), cs = fem_critical_time_step(all_stiff);
  EXPECT_DOUBLE_EQ(cm.critical, cs.critical);
  EXPECT_DOUBLE_EQ(cm.wave_speed, cs.wave_speed);
  EXPECT_EQ(mixed.material_index(cm.element), 1);
  EXPECT_NEAR(fem_critical_time_step(soft).critical / cm.critical, 2.0, 1e-12);  // c grows with sqrt(E)
}

TEST(FemExplicitDynamics, CriticalStepFromTheSmallestElement) {
  const FemModel m = beam();
  const auto cs = fem_critical_time_step(m, 0.5);
  const double c = std::sqrt((m.lame[0].lambda + 2 * m.lame[0].mu) / m.materials[0].density);
  EXPECT_NEAR(cs.wave_speed, c, 1e-9 * c);
  // Kuhn tets of a 2 mm cube: the smallest altitude is 2 / sqrt(2) (3 V / largest face area).
  EXPECT_NEAR(cs.length, 2 / std::sqrt(2.0), 1e-9);
  EXPECT_NEAR(cs.dt, 0.5 * cs.length / c, 1e-15);
  FemDynamicsOptions o;
  o.dt = 1.01 * cs.critical;
  try {
    FemExplicitDynamics d(m, o);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "dt");
  }
  EXPECT_THROW(fem_critical_time_step(m, 0), InputError);
}

TEST(FemExplicitDynamics, FreeFallIsExactForConstantAcceleration) {
  const FemModel m = beam({2, 1, 1}, {4, 2, 2});
  FemDynamicsOptions o;
  o.gravity = {0, 0, -9810};
  FemExplicitDynamics d(m, o);
  d.step(20);
  const double expected = -9810 * d.dt() * d.dt() * 20 * 21 / 2;  // u_n = g dt^2 n (n + 1) / 2
  for (int32_t i = 0; i < m.node_count(); ++i) EXPECT_NEAR(d.displacements()[3 * i + 2], expected, 1e-5 * std::abs(expected));
  EXPECT_NEAR(d.time(), 20 * d.dt(), 1e-15);
}

TEST(FemExplicitDynamics, DampedRunSettlesToTheStaticSolution) {
  const FemModel m = beam();
  FemBoundaryConditions bc;
  bc.fixed_nodes = nodes_where(m, 0, 0.0);
  FemLoads loads;
  loads.gravity = {0, 0, -9810};
  const auto stat = solve_fem_static(m, bc, loads);
  FemDynamicsOptions o;
  o.gravity = loads.gravity;
  o.mass_damping = 300;  // 1/s: about critical for the first bending mode (~24 Hz)
  FemExplicitDynamics d(m, o);
  d.set_fixed_nodes(bc.fixed_nodes);
  const int steps = static_cast<int>(std::ceil(0.3 / d.dt()));
  d.step(steps);
  const auto u = d.displacements();
  double err = 0, scale = 0;
  for (std::size_t k = 0; k < u.size(); ++k) {
    err = std::max(err, std::abs(u[k] - stat.displacements[k]));
    scale = std::max(scale, std::abs(stat.displacements[k]));
  }
  std::printf("damped dynamics (%d steps of %.3g s) vs static: max difference %.3g mm of a %.3g mm sag\n", steps, d.dt(),
              err, scale);
  EXPECT_GT(scale, 0.1);
  EXPECT_LT(err, 2e-3 * scale);
  EXPECT_LT(d.kinetic_energy(), 1e-6 * d.strain_energy());
  // The float forces of the step agree with the double forces of fem_forces.
  std::vector<double> fd;
  fem_internal_forces(m, u, fd);
  const auto ff = d.internal_forces();
  double fmax = 0, ferr = 0;
  for (std::size_t k = 0; k < fd.size(); ++k) {
    fmax = std::max(fmax, std::abs(fd[k]));
    ferr = std::max(ferr, std::abs(fd[k] - ff[k]));
  }
  EXPECT_LT(ferr, 1e-3 * fmax);
}

TEST(FemExplicitDynamics, ElementInversionIsARuntimeErrorAndLeavesNoNaN) {
  const FemModel m = beam();
  FemExplicitDynamics d(m);
  d.set_fixed_nodes(nodes_where(m, 0, 0.0));
  d.step(5);
  const int32_t corner = m.node_count() - 1;  // (12, 4, 4): yanked through the beam in one step
  d.set_prescribed({corner}, {-20.0, -6.0, -6.0});
  try {
    d.step(3);
    FAIL() << "no inversion reported";
  } catch (const RuntimeError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("inverted"), std::string::npos) << msg;
    EXPECT_NE(msg.find("element"), std::string::npos) << msg;
    EXPECT_NE(msg.find("t = "), std::string::npos) << msg;
    EXPECT_NE(msg.find("suggested"), std::string::npos) << msg;
  }
  for (double v : d.displacements()) EXPECT_TRUE(std::isfinite(v));
}

TEST(FemExplicitDynamics, BitIdenticalForAnyThreadCount) {
  const FemModel m = beam({16, 8, 8}, {32, 16, 16});  // 6,144 tets
  std::vector<std::vector<Real>> results;
  for (int threads : {1, 2, 3}) {
    FemDynamicsOptions o;
    o.threads = threads;
    o.gravity = {0, -9810, 0};
    o.mass_damping = 10;
    FemExplicitDynamics d(m, o);
    d.set_fixed_nodes(nodes_where(m, 0, 0.0));
    std::vector<int32_t> grab;
    std::vector<double> disp;
    for (int32_t i : nodes_where(m, 0, 32.0)) {
      grab.push_back(i);
      disp.insert(disp.end(), {0.0, 0.0, 0.5});
    }
    d.set_prescribed(grab, disp);
    d.step(40);
    results.push_back(d.raw_displacements());
  }
  EXPECT_EQ(results[0], results[1]);
  EXPECT_EQ(results[0], results[2]);
}

TEST(FemExplicitDynamics, SphereProbeKeepsNodesOutside) {
  const FemModel m = beam();
  FemDynamicsOptions o;
  o.mass_damping = 200;
  FemExplicitDynamics d(m, o);
  d.set_fixed_nodes(nodes_where(m, 0, 0.0));
  const std::array<double, 3> centre{10, 2, 4 + 1.5 - 0.6};  // 0.6 mm into the top face near the tip
  d.set_contact_sphere(centre, 1.5);
  d.step(200);
  EXPECT_GT(d.contacts(), 0);
  const auto p = d.positions();
  for (int32_t i = 0; i < m.node_count(); ++i) {
    const double r = std::hypot(p[3 * i] - centre[0], p[3 * i + 1] - centre[1], p[3 * i + 2] - centre[2]);
    EXPECT_GE(r, 1.5 - 1e-4);
  }
  EXPECT_THROW(d.set_contact_sphere(centre, -1), InputError);
  EXPECT_THROW(d.set_prescribed({0}, {1.0}), InputError);
}

TEST(FemExplicitDynamics, InstrumentKeepsNodesOutAsTheSphereDoes) {
  // The sphere probe above as an instrument mesh (an icosphere within 0.01 mm of it, 0.1 mm grid):
  // no free node is deeper in it than 0.4 grid spacings after the steps, and the beam takes the same
  // shape as under the sphere to within the mesh's chord and the grid's rounding.
  const FemModel m = beam();
  FemDynamicsOptions o;
  o.mass_damping = 200;
  FemExplicitDynamics with_mesh(m, o), with_sphere(m, o);
  with_mesh.set_fixed_nodes(nodes_where(m, 0, 0.0));
  with_sphere.set_fixed_nodes(nodes_where(m, 0, 0.0));
  const std::array<double, 3> centre{10, 2, 4 + 1.5 - 0.6};
  const Instrument ball = make_instrument(test::icosphere(1.5, 4), "ball", 0.1);
  const InstrumentView v = instrument_view(ball, kIdentityRotation, centre);
  with_mesh.set_contact_instruments({v});
  with_sphere.set_contact_sphere(centre, 1.5);
  with_mesh.step(200);
  with_sphere.step(200);
  EXPECT_GT(with_mesh.contacts(), 0);
  const auto p = with_mesh.positions(), q = with_sphere.positions();
  double deepest = 0, worst = 0;
  for (int32_t i = 0; i < m.node_count(); ++i) {
    deepest = std::max(deepest, -instrument_signed_distance(v, p[3 * i], p[3 * i + 1], p[3 * i + 2]));
    for (int a = 0; a < 3; ++a) worst = std::max(worst, std::abs(p[3 * i + a] - q[3 * i + a]));
  }
  EXPECT_LT(deepest, 0.04);
  EXPECT_LT(worst, 0.02);
  with_mesh.set_contact_instruments({});
  InstrumentView empty;
  EXPECT_THROW(with_mesh.set_contact_instruments({empty}), InputError);
}

}  // namespace
}  // namespace ctsurg::sim

namespace ctsurg::sim {
namespace {

// The energy-growth guard: free fall from rest quadruples the kinetic energy between the checks at
// steps 16 and 32 (v grows linearly), above an allowed growth of 1.5, so the run stops after step 32
// with the message, the state finite.
TEST(FemExplicitDynamics, EnergyGrowthAboveTheLimitStopsTheRun) {
  const FemModel m = test::fem_box_model(FemLaw::linear, {2, 2, 2}, {4, 4, 4}, 3e4, 0.3);
  FemDynamicsOptions o;
  o.gravity = {0, 0, -9810};
  o.energy_growth = 1.5;
  o.energy_floor = 0;
  FemExplicitDynamics d(m, o);
  try {
    d.step(100);
    ADD_FAILURE() << "no energy growth reported";
  } catch (const RuntimeError& e) {
    EXPECT_NE(std::string(e.what()).find("kinetic energy grew"), std::string::npos) << e.what();
  }
  EXPECT_EQ(d.steps_taken(), 32);
  for (double u : d.displacements()) EXPECT_TRUE(std::isfinite(u));
}

}  // namespace
}  // namespace ctsurg::sim
