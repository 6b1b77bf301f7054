// Tests of ctsurg/sim/fem/fem_implicit_dynamics.h: free fall exact, a run settling to the static
// solution for every law, frame-sized steps stable on stiff tissue with the energy decaying after a
// release, Rayleigh damping making the decay faster; the midpoint scheme keeping a bar's first mode
// (frequency and set damping ratio within 2 %) and the energy of a large release; a grab held at its target, supports of single
// components, a failed step retried in halves and, past the limit, a RuntimeError that leaves the state.
#include "ctsurg/sim/fem/fem_implicit_dynamics.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/fem/fem_forces.h"
#include "ctsurg/sim/fem/fem_static_solver.h"
#include "fem_test_models.h"

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace ctsurg::sim {
namespace {

using test::max_abs;
using test::max_abs_difference;

using test::nodes_where;

FemModel implicit_beam(FemLaw law, double youngs_pa = 3e4, std::array<int, 3> cells = {6, 2, 2}) {
  return test::fem_box_model(law, cells, {12, 4, 4}, youngs_pa, 0.3);
}

TEST(FemImplicitDynamics, FreeFallIsExactForConstantAcceleration) {
  // A rigid translation strains nothing; backward Euler gives v_n = g h n, u_n = g h^2 n (n + 1) / 2.
  for (auto law : {FemLaw::linear, FemLaw::neo_hookean, FemLaw::corotational}) {
    const FemModel m = implicit_beam(law, 3e4, {2, 1, 1});
    FemImplicitOptions o;
    o.gravity = {0, 0, -9810};
    FemImplicitDynamics d(m, o);
    d.step(10);
    const double h = d.dt();
    const double expected = -9810 * h * h * 10 * 11 / 2;
    for (int32_t i = 0; i < m.node_count(); ++i) {
      EXPECT_NEAR(d.displacements()[3 * i + 2], expected, 1e-6 * std::abs(expected)) << fem_law_name(law);
      EXPECT_NEAR(d.velocities()[3 * i + 2], -9810 * h * 10, 1e-6 * 9810 * h * 10);
      EXPECT_NEAR(d.displacements()[3 * i], 0, 1e-9);
    }
    EXPECT_NEAR(d.time(), 10 * h, 1e-15);
    EXPECT_EQ(d.steps_taken(), 10);
  }
}

TEST(FemImplicitDynamics, FrameStepsSettleToTheStaticSolutionForEveryLaw) {
  // A cantilever sagging under gravity, steps of a frame (1/60 s, thousands of times the explicit
  // critical step): backward Euler's own damping settles it without Rayleigh damping, to the static
  // equilibrium of the same law.
  for (auto law : {FemLaw::linear, FemLaw::stvk, FemLaw::neo_hookean,
                   FemLaw::corotational}) {
    const FemModel m = implicit_beam(law);
    FemBoundaryConditions bc;
    bc.fixed_nodes = nodes_where(m, 0, 0.0);
    FemLoads loads;
    loads.gravity = {0, 0, -9810};
    FemStaticOptions so;
    so.tolerance_mm = 1e-7;
    const auto stat = solve_fem_static(m, bc, loads, so);
    FemImplicitOptions o;
    o.gravity = loads.gravity;
    o.newton.tolerance_mm = 1e-7;
    FemImplicitDynamics d(m, o);
    d.set_supports(bc.fixed_nodes);
    const auto rep = d.step(120);
    const double err = max_abs_difference(d.displacements(), stat.displacements);
    const double sag = max_abs(stat.displacements);
    std::printf("%s: 120 implicit steps of 1/60 s vs static: %.3g mm of a %.3g mm sag, %d Newton iterations, %d factorisations\n",
                fem_law_name(law), err, sag, rep.newton_iterations, rep.factorizations);
    EXPECT_GT(sag, 0.1);
    EXPECT_LT(err, 1e-4 * sag) << fem_law_name(law);
    EXPECT_LT(d.kinetic_energy(), 1e-8 * d.strain_energy());
    EXPECT_EQ(rep.substeps, 1);
  }
}

// Kinetic + strain energy after each step, from a grab released at rest.
std::vector<double> energies_after_release(const FemModel& m, double mass_damping, double stiffness_damping, int steps) {
  FemImplicitOptions o;
  o.mass_damping = mass_damping;
  o.stiffness_damping = stiffness_damping;
  o.newton.tolerance_mm = 1e-8;  // the integrator's dissipation, not the solver's tolerance
  FemImplicitDynamics d(m, o);
  d.set_supports(nodes_where(m, 0, 0.0));
  const auto tip = nodes_where(m, 0, 12.0);
  d.set_prescribed(tip, std::vector<double>(3 * tip.size(), 0.0));
  std::vector<double> target(3 * tip.size(), 0.0);
  for (std::size_t g = 0; g < tip.size(); ++g) target[3 * g + 2] = 3.0;  // 3 mm up, a quarter of the length
  d.set_prescribed(tip, target);
  d.step(1);
  d.clear_prescribed();
  std::vector<double> e;
  e.push_back(d.kinetic_energy() + d.strain_energy());
  for (int k = 0; k < steps; ++k) {
    d.step(1);
    for (double v : d.displacements()) EXPECT_TRUE(std::isfinite(v));
    e.push_back(d.kinetic_energy() + d.strain_energy());
  }
  return e;
}

TEST(FemImplicitDynamics, FrameStepsOnStiffTissueAreStableAndTheEnergyOnlyDecays) {
  // 1 MPa (cartilage-like, 30 times the heart's stiffness): the explicit critical step is about 2 us;
  // a frame is 8,000 of them. After a release the total energy never grows (backward Euler dissipates).
  for (auto law : {FemLaw::linear, FemLaw::neo_hookean, FemLaw::corotational}) {
    const FemModel m = implicit_beam(law, 1e6);
    const auto e = energies_after_release(m, 0, 0, 30);
    for (std::size_t k = 1; k < e.size(); ++k)  // to round-off (1e-12 of the start)
      EXPECT_LE(e[k], e[k - 1] * (1 + 1e-9) + 1e-12 * e[0]) << fem_law_name(law) << " step " << k;
    EXPECT_LT(e.back(), 1e-3 * e.front()) << fem_law_name(law);
    std::printf("%s, 1 MPa: energy %.3g nJ after release, %.3g after 1 step, %.3g after 30 steps of 1/60 s\n",
                fem_law_name(law), e[0], e[1], e.back());
  }
}

TEST(FemImplicitDynamics, RayleighDampingRemovesEnergyFaster) {
  // A soft beam (3 kPa) whose first mode is slow enough (wh < 1) to ring under backward Euler alone.
  const FemModel m = implicit_beam(FemLaw::neo_hookean, 3e3);
  const auto none = energies_after_release(m, 0, 0, 10);
  const auto mass = energies_after_release(m, 20, 0, 10);
  const auto stiff = energies_after_release(m, 0, 0.02, 10);
  std::printf("energy left after 10 steps: no Rayleigh damping %.3g, alpha 20/s %.3g, beta 0.02 s %.3g (of %.3g)\n", none.back(),
              mass.back(), stiff.back(), none.front());
  EXPECT_LT(mass.back(), none.back());
  EXPECT_LT(stiff.back(), none.back());
  EXPECT_GT(none.back(), 1e-6 * none.front());  // the undamped decay is visible but not instant
}

// The lowest mode of K phi = w^2 M phi on the free components of a linear-law model (K by columns from
// the internal forces of unit displacements: exact for the linear law), phi M-normalised (#N x 3, 0 on
// the held nodes).
struct LowestMode {
  double omega = 0;  // rad/s
  std::vector<double> shape;
};

LowestMode lowest_mode(const FemModel& m, const std::vector<int32_t>& held_nodes) {
  std::vector<uint8_t> held(3 * static_cast<size_t>(m.node_count()), 0);
  for (const int32_t i : held_nodes) held[3 * i] = held[3 * i + 1] = held[3 * i + 2] = 1;
  std::vector<int32_t> free;
  for (int32_t c = 0; c < 3 * m.node_count(); ++c)
    if (!held[c]) free.push_back(c);
  const auto nf = static_cast<Eigen::Index>(free.size());
  Eigen::MatrixXd k(nf, nf);
  Eigen::VectorXd mass(nf);
  std::vector<double> u(held.size(), 0.0), f;
  for (Eigen::Index j = 0; j < nf; ++j) {
    u[free[j]] = 1;
    fem_internal_forces(m, u, f);
    u[free[j]] = 0;
    for (Eigen::Index i = 0; i < nf; ++i) k(i, j) = -f[free[i]];
    mass[j] = m.node_mass[free[j] / 3];
  }
  const Eigen::MatrixXd sym = 0.5 * (k + k.transpose());
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(sym, Eigen::MatrixXd(mass.asDiagonal()));
  LowestMode mode;
  mode.omega = std::sqrt(eig.eigenvalues()[0]);
  mode.shape.assign(held.size(), 0.0);
  for (Eigen::Index i = 0; i < nf; ++i) mode.shape[free[i]] = eig.eigenvectors()(i, 0);
  return mode;
}

// The frequency and damping ratio of a sampled free decay q_n: the recurrence q_{n+1} = a q_n + b q_{n-1}
// that any linear two-state scheme obeys, fitted by least squares, its roots r e^{+-i theta}: the
// scheme's own damped frequency theta / h and decay rate -ln r / h (exact up to round-off, no peak picking).
struct ModalResponse {
  double omega = 0;  // undamped, sqrt(sigma^2 + omega_d^2), rad/s
  double zeta = 0;   // sigma / omega
};

ModalResponse modal_response(const std::vector<double>& q, double h) {
  Eigen::MatrixXd a(static_cast<Eigen::Index>(q.size() - 2), 2);
  Eigen::VectorXd b(a.rows());
  for (Eigen::Index n = 0; n < a.rows(); ++n) {
    a(n, 0) = q[n + 1];
    a(n, 1) = q[n];
    b[n] = q[n + 2];
  }
  const Eigen::Vector2d c = a.colPivHouseholderQr().solve(b);
  const double r = std::sqrt(-c[1]);  // roots of z^2 - c0 z - c1: |z|^2 = -c1
  const double theta = std::acos(std::clamp(c[0] / (2 * r), -1.0, 1.0));
  const double sigma = -std::log(r) / h, omega_d = theta / h;
  ModalResponse out;
  out.omega = std::hypot(sigma, omega_d);
  out.zeta = sigma / out.omega;
  return out;
}

TEST(FemImplicitDynamics, MidpointKeepsTheFirstModesFrequencyAndTheSetDampingRatio) {
  // A soft cantilever (8 x 12 x 80 mm, 30 kPa: its first bending mode near 1-2 Hz, as an organ's lobe)
  // released from 1 mm in that mode's shape, steps of a frame. The modal coordinate q = phi^T M u of
  // every step gives the scheme's frequency and damping ratio, to compare with the eigenproblem's
  // frequency and the Rayleigh ratio set (alpha = 2 zeta omega_1). Target (issue 32): within 2 %.
  const FemModel m = test::fem_box_model(FemLaw::linear, {2, 3, 16}, {8, 12, 80}, 3e4, 0.45);
  const auto base = nodes_where(m, 2, 0.0);
  const LowestMode mode = lowest_mode(m, base);
  const double scale = 1.0 / max_abs(mode.shape);  // 1 mm at the largest
  std::vector<double> u0(mode.shape.size());
  for (size_t c = 0; c < u0.size(); ++c) u0[c] = scale * mode.shape[c];
  for (const double zeta : {0.0, 0.05}) {
    for (const auto scheme : {FemImplicitScheme::midpoint, FemImplicitScheme::backward_euler}) {
      FemImplicitOptions o;
      o.scheme = scheme;
      o.mass_damping = 2 * zeta * mode.omega;
      o.newton.tolerance_mm = 1e-10;
      FemImplicitDynamics d(m, o);
      d.set_supports(base);
      d.restore_state(u0, std::vector<double>(u0.size(), 0.0), 0, 0);
      std::vector<double> q;
      for (int n = 0; n < 240; ++n) {  // 4 s: several periods
        double qn = 0;
        for (size_t c = 0; c < u0.size(); ++c) qn += mode.shape[c] * m.node_mass[c / 3] * d.displacements()[c];
        q.push_back(qn);
        d.step(1);
      }
      const ModalResponse r = modal_response(q, d.dt());
      const bool midpoint = scheme == FemImplicitScheme::midpoint;
      std::printf("%s, zeta %.2f: first mode %.4f rad/s (%.3f Hz, w h %.3f): scheme's frequency %.4f rad/s (%+.2f %%), damping ratio %.4f\n",
                  midpoint ? "midpoint" : "backward Euler", zeta, mode.omega, mode.omega / (2 * M_PI), mode.omega * d.dt(), r.omega,
                  100 * (r.omega / mode.omega - 1), r.zeta);
      if (midpoint) {
        EXPECT_NEAR(r.omega / mode.omega, 1, 0.02) << "zeta " << zeta;
        EXPECT_NEAR(r.zeta, zeta, zeta > 0 ? 0.02 * zeta : 1e-6) << "the step must not damp";
      } else {
        EXPECT_GT(r.zeta - zeta, 0.02 * std::max(zeta, 0.05)) << "backward Euler's own damping (the reason for midpoint)";
      }
    }
  }
}

// Kinetic + strain energy after each step of a release from the static equilibrium of a grab (the tip
// moved 3 mm up): no velocity to start with, so the energy to keep is the strain energy at rest.
std::vector<double> energies_after_static_release(const FemModel& m, double stiffness_damping, int steps, FemImplicitScheme scheme) {
  FemBoundaryConditions bc;
  bc.fixed_nodes = nodes_where(m, 0, 0.0);
  bc.prescribed_nodes = nodes_where(m, 0, 12.0);
  for (std::size_t g = 0; g < bc.prescribed_nodes.size(); ++g) bc.prescribed_displacements.insert(bc.prescribed_displacements.end(), {0, 0, 3});
  FemStaticOptions so;
  so.tolerance_mm = 1e-9;
  const auto bent = solve_fem_static(m, bc, {}, so);
  FemImplicitOptions o;
  o.scheme = scheme;
  o.stiffness_damping = stiffness_damping;
  o.newton.tolerance_mm = 1e-5;
  FemImplicitDynamics d(m, o);
  d.set_supports(bc.fixed_nodes);
  d.restore_state(bent.displacements, std::vector<double>(bent.displacements.size(), 0.0), 0, 0);
  std::vector<double> e{d.strain_energy()};
  for (int k = 0; k < steps; ++k) {
    d.step(1);
    e.push_back(d.kinetic_energy() + d.strain_energy());
  }
  return e;
}

TEST(FemImplicitDynamics, MidpointStepsKeepTheEnergyAndNeverGainItWithStiffnessDamping) {
  // A large release (3 mm on a 12 mm beam) on the nonlinear laws, 60 steps of a frame: without Rayleigh
  // damping midpoint with the discrete gradient keeps the energy (to the Newton tolerance; the plain
  // midpoint rule doubled it here within 60 steps), where backward Euler loses nearly all of it; with
  // stiffness damping the energy falls step after step.
  for (auto law : {FemLaw::neo_hookean, FemLaw::corotational}) {
    const FemModel m = implicit_beam(law, 3e3);
    const auto kept = energies_after_static_release(m, 0, 60, FemImplicitScheme::midpoint);
    const auto damped = energies_after_static_release(m, 0.01, 60, FemImplicitScheme::midpoint);
    const auto euler = energies_after_static_release(m, 0, 60, FemImplicitScheme::backward_euler);
    double lo = kept.front(), hi = kept.front();
    for (const double e : kept) {
      lo = std::min(lo, e);
      hi = std::max(hi, e);
    }
    std::printf("%s, 3 kPa: energy %.6g nJ released; after 60 steps of 1/60 s: midpoint %.6g (range %.6g .. %.6g), with beta 0.01 s %.3g, "
                "backward Euler %.3g\n",
                fem_law_name(law), kept.front(), kept.back(), lo, hi, damped.back(), euler.back());
    EXPECT_GT(lo, (1 - 1e-4) * kept.front()) << fem_law_name(law);
    EXPECT_LT(hi, (1 + 1e-4) * kept.front()) << fem_law_name(law);
    for (std::size_t k = 1; k < damped.size(); ++k)
      EXPECT_LE(damped[k], damped[k - 1] * (1 + 1e-9) + 1e-12 * damped[0]) << fem_law_name(law) << " step " << k;
    EXPECT_LT(damped.back(), 0.5 * damped.front());
    EXPECT_LT(euler.back(), 0.01 * euler.front());
  }
}

TEST(FemImplicitDynamics, AGrabIsHeldAtItsTargetAndComponentSupportsHoldOnlyTheirAxis) {
  const FemModel m = implicit_beam(FemLaw::neo_hookean);
  FemImplicitDynamics d(m);
  // The root on a roller in x only, plus what removes the remaining rigid motions.
  const auto root = nodes_where(m, 0, 0.0);
  std::vector<int32_t> components;
  for (int32_t i : root) components.push_back(3 * i);
  components.push_back(3 * root[0] + 1);
  components.push_back(3 * root[0] + 2);
  components.push_back(3 * root[1] + 2);
  components.push_back(3 * root[2] + 1);
  d.set_supports({}, components);
  const auto tip = nodes_where(m, 0, 12.0);
  std::vector<double> target(3 * tip.size(), 0.0);
  for (std::size_t g = 0; g < tip.size(); ++g) target[3 * g] = 1.2;  // a 10 % stretch
  d.set_prescribed(tip, target);
  d.step(60);
  for (std::size_t g = 0; g < tip.size(); ++g)
    for (int a = 0; a < 3; ++a) EXPECT_DOUBLE_EQ(d.displacements()[3 * tip[g] + a], target[3 * g + a]);
  double lateral = 0;
  for (int32_t i : root) {
    EXPECT_EQ(d.displacements()[3 * i], 0.0);
    lateral = std::max(lateral, std::abs(d.displacements()[3 * i + 1]) + std::abs(d.displacements()[3 * i + 2]));
  }
  EXPECT_GT(lateral, 1e-3);  // the root contracts sideways (Poisson) on its roller: y and z are free
  EXPECT_THROW(d.set_supports({}, {3 * m.node_count()}), InputError);
  EXPECT_THROW(d.set_supports({-1}), InputError);
}

TEST(FemImplicitDynamics, AFailedStepIsRetriedInHalvesAndPastTheLimitLeavesTheState) {
  const FemModel m = implicit_beam(FemLaw::neo_hookean);
  const auto root = nodes_where(m, 0, 0.0);
  const auto tip = nodes_where(m, 0, 12.0);
  std::vector<double> target(3 * tip.size(), 0.0);
  for (std::size_t g = 0; g < tip.size(); ++g) target[3 * g + 2] = 8.0;  // two thirds of the length in one frame
  FemImplicitOptions o;
  o.newton.max_newton_iterations = 3;
  o.max_halvings = 0;
  {
    FemImplicitDynamics d(m, o);
    d.set_supports(root);
    d.step(2);
    const auto before = d.displacements();
    d.set_prescribed(tip, target);
    try {
      d.step(1);
      FAIL() << "a step that cannot converge in 3 Newton iterations was accepted";
    } catch (const RuntimeError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find("t = "), std::string::npos) << msg;
      EXPECT_NE(msg.find("sub-steps"), std::string::npos) << msg;
    }
    EXPECT_EQ(d.displacements(), before);
    EXPECT_EQ(d.steps_taken(), 2);
  }
  o.max_halvings = 6;
  FemImplicitDynamics d(m, o);
  d.set_supports(root);
  d.set_prescribed(tip, target);
  const auto rep = d.step(1);
  EXPECT_GT(rep.substeps, 1);
  EXPECT_EQ(d.steps_taken(), 1);
  for (double v : d.displacements()) EXPECT_TRUE(std::isfinite(v));
}

TEST(FemImplicitDynamics, OptionsOutOfRangeNameTheirField) {
  const FemModel m = implicit_beam(FemLaw::linear, 3e4, {2, 1, 1});
  const auto field_of = [&](const FemImplicitOptions& o) -> std::string {
    try {
      FemImplicitDynamics d(m, o);
    } catch (const InputError& e) {
      return e.field();
    }
    return "";
  };
  FemImplicitOptions o;
  o.dt = 0;
  EXPECT_EQ(field_of(o), "dt");
  o = {};
  o.mass_damping = -1;
  EXPECT_EQ(field_of(o), "mass_damping");
  o = {};
  o.stiffness_damping = std::nan("");
  EXPECT_EQ(field_of(o), "stiffness_damping");
  o = {};
  o.gravity = {0, INFINITY, 0};
  EXPECT_EQ(field_of(o), "gravity");
  o = {};
  o.max_halvings = 21;
  EXPECT_EQ(field_of(o), "max_halvings");
  FemImplicitDynamics d(m);
  EXPECT_THROW(d.set_external_forces({1.0, 2.0}), InputError);
  EXPECT_THROW(d.set_prescribed({0}, {1.0}), InputError);
  EXPECT_THROW(d.step(-1), InputError);
}

}  // namespace
}  // namespace ctsurg::sim
