// The FEM on a CUDA device against the CPU (label gpu): FemExplicitDynamics with Backend::cuda
// (fem_explicit_dynamics.h) and solve_fem_static with Backend::cuda (fem_static_solver.h, its conjugate
// gradient on the device). Every test skips, naming the reason, on a machine without a CUDA device;
// bench/gpu/run.sh runs them on a GPU machine, also under compute-sanitizer.
//
// Tolerances of the explicit step. The device runs the CPU's per-element and per-node functions,
// compiled without FMA contraction on both sides (-fmad=false, -ffp-contract=off), with IEEE division
// and square root (nvcc's defaults) and no flush to zero; each node gathers its corner forces in the
// same CSR order. For the linear and St. Venant-Kirchhoff materials every operation of a step is a
// correctly rounded +, -, x or / in the same order, so the bits should be the CPU's; the test allows
// kStepUlps float ulps of the largest displacement. Neo-Hookean calls logf (ln J), which CUDA's and
// glibc's libraries may round differently by an ulp; that difference enters every element's stress
// and accumulates over the compared steps, so its allowance is kNeoHookeanStepUlps. Over 1,000 steps
// (gravity, a moving grab, a contact sphere, mass damping) the run is checked to kFemRunTolerance mm,
// 0.05% of the 2 mm cell, as the spring-model device tests do.
//
// Tolerances of the static solve. The device CG is Eigen's iteration in double (device_conjugate_
// gradient.h); only the order of the dot products' additions differs, so both solutions agree to the
// CG's accuracy: with cg_tolerance 1e-12 and a Jacobi-preconditioned condition number of the small box
// below 1e4, to kStaticRelative of the largest displacement; CG iteration counts may differ by a few
// (rounding changes when the recursive residual crosses the threshold): kCgIterationSlack.
#include "ctsurg/sim/fem/fem_explicit_dynamics.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/base/backend.h"
#include "ctsurg/sim/fem/fem_box_mesh.h"
#include "ctsurg/sim/fem/fem_forces.h"
#include "ctsurg/sim/fem/fem_static_solver.h"
#include "fem_test_models.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace ctsurg::sim {
namespace {

using test::max_abs;
using test::max_abs_difference;

constexpr double kStepUlps = 4;
constexpr double kNeoHookeanStepUlps = 32;
constexpr double kFemRunTolerance = 1e-3;  // mm
constexpr double kStaticRelative = 1e-8;
constexpr int kCgIterationSlack = 3;    // or 3 % of the CPU's count, whichever is larger

class FemDeviceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!cuda_built()) GTEST_SKIP() << "this build has no CUDA (CTSURG_CUDA=OFF or no nvcc)";
    if (cuda_device_count() == 0) GTEST_SKIP() << "no CUDA device on this machine";
  }
};

FemModel box_model(FemLaw material, std::array<int, 3> cells, std::array<double, 3> size) {
  return test::fem_box_model(material, cells, size);
}

using test::nodes_where;

const char* name(FemLaw m) {
  return m == FemLaw::linear ? "linear" : m == FemLaw::stvk ? "stvk" : "neo_hookean";
}

// The tools of the 12 x 8 x 8 mm box: the x = 0 face fixed, the top edge of the x = 12 face grabbed
// and lifted by `lift` mm.
std::vector<int32_t> grabbed_edge(const FemModel& m) {
  std::vector<int32_t> grab;
  for (int32_t i : nodes_where(m, 0, 12.0))
    if (m.nodes[3 * i + 2] > 7.9) grab.push_back(i);
  return grab;
}

void lift_edge(FemExplicitDynamics& d, const FemModel& m, double lift) {
  const auto grab = grabbed_edge(m);
  std::vector<double> disp;
  for (std::size_t g = 0; g < grab.size(); ++g) disp.insert(disp.end(), {0.0, 0.0, lift});
  d.set_prescribed(grab, disp);
}

TEST_F(FemDeviceTest, ExplicitStepsMatchTheCpuStepByStep) {
  for (auto material : {FemLaw::linear, FemLaw::stvk, FemLaw::neo_hookean}) {
    const FemModel m = box_model(material, {6, 4, 4}, {12, 8, 8});
    FemDynamicsOptions o;
    o.gravity = {0, 0, -9810};
    FemExplicitDynamics cpu(m, o, Backend::cpu), gpu(m, o, Backend::cuda);
    for (FemExplicitDynamics* d : {&cpu, &gpu}) {
      d->set_fixed_nodes(nodes_where(m, 0, 0.0));
      lift_edge(*d, m, 0.2);
    }
    const double ulps = material == FemLaw::neo_hookean ? kNeoHookeanStepUlps : kStepUlps;
    for (int k = 1; k <= 20; ++k) {
      cpu.step(1);
      gpu.step(1);
      const auto u = cpu.displacements();
      const double tolerance = ulps * std::numeric_limits<Real>::epsilon() * max_abs(u);
      ASSERT_LE(max_abs_difference(u, gpu.displacements()), tolerance) << name(material) << ", step " << k;
    }
    EXPECT_GT(max_abs(cpu.displacements()), 0.1);  // the grab moved the tissue
    EXPECT_EQ(gpu.steps_taken(), cpu.steps_taken());
    EXPECT_EQ(gpu.time(), cpu.time());
    // The accessors: energies (a device sum vs a serial one) and the step's forces of the same state.
    EXPECT_NEAR(gpu.kinetic_energy(), cpu.kinetic_energy(), 1e-5 * cpu.kinetic_energy()) << name(material);
    EXPECT_NEAR(gpu.strain_energy(), cpu.strain_energy(), 1e-5 * cpu.strain_energy()) << name(material);
    const auto f_cpu = cpu.internal_forces(), f_gpu = gpu.internal_forces();
    double f_max = 0;
    for (Real f : f_cpu) f_max = std::max(f_max, std::abs(double(f)));
    EXPECT_LE(max_abs_difference(f_cpu, f_gpu), 1e-4 * f_max) << name(material);
    EXPECT_LE(max_abs_difference(cpu.positions(), gpu.positions()), 1e-5) << name(material);
  }
}

// 1,000 steps: gravity, mass damping, a grab lifted in small increments, a sphere pressing on the top.
// Steps are taken in calls of 10 (partial chunks: direct launches) and then in one call of 500 (whole
// chunks: graph replays), so both launch paths are compared.
void run_with_tools(FemExplicitDynamics& d, const FemModel& m) {
  d.set_fixed_nodes(nodes_where(m, 0, 0.0));
  d.set_contact_sphere({5, 3, 8 + 3.0 - 0.6}, 3.0);  // 0.6 mm into the top face, over 4 nodes
  for (int call = 1; call <= 50; ++call) {
    lift_edge(d, m, 0.01 * call);
    d.step(10);
  }
  d.step(500);
}

TEST_F(FemDeviceTest, ThousandStepsWithGravityGrabAndSphereMatchTheCpu) {
  for (auto material : {FemLaw::linear, FemLaw::stvk, FemLaw::neo_hookean}) {
    const FemModel m = box_model(material, {6, 4, 4}, {12, 8, 8});
    FemDynamicsOptions o;
    o.gravity = {0, 0, -9810};
    o.mass_damping = 50;
    FemExplicitDynamics cpu(m, o, Backend::cpu), gpu(m, o, Backend::cuda), again(m, o, Backend::cuda);
    run_with_tools(cpu, m);
    run_with_tools(gpu, m);
    run_with_tools(again, m);
    EXPECT_EQ(gpu.steps_taken(), 1000);
    EXPECT_EQ(gpu.time(), cpu.time());
    EXPECT_LE(max_abs_difference(cpu.displacements(), gpu.displacements()), kFemRunTolerance) << name(material);
    EXPECT_GT(cpu.contacts(), 0) << name(material);
    // A node on the sphere's surface is inside or not by its last bits: allow a couple to differ.
    EXPECT_LE(std::abs(gpu.contacts() - cpu.contacts()), 2) << name(material);
    EXPECT_NEAR(gpu.strain_energy(), cpu.strain_energy(), 1e-3 * cpu.strain_energy()) << name(material);
    // Deterministic: two device runs give the same bits.
    EXPECT_EQ(gpu.raw_displacements(), again.raw_displacements()) << name(material);
    EXPECT_EQ(gpu.kinetic_energy(), again.kinetic_energy()) << name(material);
  }
}

// A node yanked through the beam: the element it inverts is reported with the CPU's message, and the
// device keeps the state before the failing step (the second step of the call), as the CPU does.
TEST_F(FemDeviceTest, InversionStopsWithTheCpuMessageAndKeepsTheStateBeforeIt) {
  const FemModel m = box_model(FemLaw::neo_hookean, {6, 2, 2}, {12, 4, 4});
  FemExplicitDynamics cpu(m, {}, Backend::cpu), gpu(m, {}, Backend::cuda);
  std::string messages[2];
  FemExplicitDynamics* runs[2] = {&cpu, &gpu};
  for (int r = 0; r < 2; ++r) {
    FemExplicitDynamics& d = *runs[r];
    d.set_fixed_nodes(nodes_where(m, 0, 0.0));
    d.step(5);
    d.set_prescribed({m.node_count() - 1}, {-20.0, -6.0, -6.0});
    try {
      d.step(3);
      ADD_FAILURE() << "no inversion reported";
    } catch (const RuntimeError& e) {
      messages[r] = e.what();
    }
  }
  EXPECT_NE(messages[1].find("element "), std::string::npos) << messages[1];
  EXPECT_NE(messages[1].find("inverted"), std::string::npos) << messages[1];
  EXPECT_EQ(messages[1], messages[0]);
  EXPECT_EQ(gpu.steps_taken(), cpu.steps_taken());
  EXPECT_EQ(gpu.time(), cpu.time());
  const auto u = gpu.displacements();
  for (double v : u) ASSERT_TRUE(std::isfinite(v));
  EXPECT_LE(max_abs_difference(cpu.displacements(), u), kNeoHookeanStepUlps * std::numeric_limits<Real>::epsilon() * max_abs(u));
  // The stop is cleared: the next call runs, meets the same inverted element and says so again.
  try {
    gpu.step(1);
    ADD_FAILURE() << "no inversion reported on the second call";
  } catch (const RuntimeError& e) {
    EXPECT_EQ(std::string(e.what()), messages[0]);
  }
}

// Free fall from rest: the kinetic energy grows 4x between the checks at steps 16 and 32, above the
// allowed 1.5x, so both backends stop after step 32 (the device inside one call of 100 steps, in graph
// replays).
TEST_F(FemDeviceTest, EnergyGrowthStopsAtTheSameCheck) {
  const FemModel m = box_model(FemLaw::linear, {2, 2, 2}, {4, 4, 4});
  FemDynamicsOptions o;
  o.gravity = {0, 0, -9810};
  o.energy_growth = 1.5;
  o.energy_floor = 0;
  FemExplicitDynamics cpu(m, o, Backend::cpu), gpu(m, o, Backend::cuda);
  std::string messages[2];
  FemExplicitDynamics* runs[2] = {&cpu, &gpu};
  for (int r = 0; r < 2; ++r) {
    try {
      runs[r]->step(100);
      ADD_FAILURE() << "no energy growth reported";
    } catch (const RuntimeError& e) {
      messages[r] = e.what();
    }
  }
  EXPECT_NE(messages[1].find("kinetic energy grew"), std::string::npos) << messages[1];
  EXPECT_EQ(cpu.steps_taken(), 32);
  EXPECT_EQ(gpu.steps_taken(), 32);
  EXPECT_EQ(gpu.time(), cpu.time());
  EXPECT_LE(max_abs_difference(cpu.displacements(), gpu.displacements()),
            kStepUlps * std::numeric_limits<Real>::epsilon() * max_abs(cpu.displacements()));
}

// The FEM paper's static experiment on a small cube: bottom fixed, the top centre grabbed down.
struct StaticProblem {
  FemModel model;
  FemBoundaryConditions bc;
};

StaticProblem grabbed_cube(FemLaw material) {
  StaticProblem p{box_model(material, {5, 5, 5}, {10, 10, 10}), {}};
  for (int32_t i = 0; i < p.model.node_count(); ++i) {
    const double* x = &p.model.nodes[3 * i];
    if (x[2] == 0) p.bc.fixed_nodes.push_back(i);
    if (std::abs(x[2] - 10) < 1e-9 && std::hypot(x[0] - 5, x[1] - 5) <= 2.1) {
      p.bc.prescribed_nodes.push_back(i);
      p.bc.prescribed_displacements.insert(p.bc.prescribed_displacements.end(), {0.0, 0.0, -0.5});
    }
  }
  return p;
}

TEST_F(FemDeviceTest, StaticSolveWithTheDeviceCgMatchesTheCpu) {
  for (auto material : {FemLaw::linear, FemLaw::neo_hookean}) {
    const StaticProblem p = grabbed_cube(material);
    FemStaticOptions o;
    o.cg_tolerance = 1e-12;
    o.inexact_newton = false;  // every Newton step at 1e-12, as the tolerance above assumes
    // The same method on both: Jacobi-preconditioned CG (the CPU would otherwise solve directly, with
    // CHOLMOD, in a few iterations: its automatic choice, which the device does not have).
    o.linear_solve = FemLinearSolve::iterative;
    const FemStaticResult cpu = solve_fem_static(p.model, p.bc, {}, o, Backend::cpu);
    const FemStaticResult gpu = solve_fem_static(p.model, p.bc, {}, o, Backend::cuda);
    const FemStaticResult again = solve_fem_static(p.model, p.bc, {}, o, Backend::cuda);
    ASSERT_TRUE(gpu.report.converged) << name(material);
    const double scale = max_abs(cpu.displacements);
    EXPECT_GT(scale, 0.4) << name(material);
    EXPECT_LE(max_abs_difference(cpu.displacements, gpu.displacements), kStaticRelative * scale) << name(material);
    EXPECT_LE(max_abs_difference(cpu.reactions, gpu.reactions), 1e-6 * max_abs(cpu.reactions)) << name(material);
    EXPECT_EQ(gpu.report.free_components, cpu.report.free_components);
    EXPECT_EQ(gpu.report.newton_iterations, cpu.report.newton_iterations) << name(material);
    ASSERT_EQ(gpu.report.cg_iterations.size(), cpu.report.cg_iterations.size()) << name(material);
    for (std::size_t k = 0; k < cpu.report.cg_iterations.size(); ++k) {
      const int c = cpu.report.cg_iterations[k], g = gpu.report.cg_iterations[k];
      EXPECT_LE(std::abs(g - c), std::max(kCgIterationSlack, c * 3 / 100)) << name(material) << ", Newton iteration " << k;
    }
    EXPECT_EQ(gpu.displacements, again.displacements) << name(material) << ": the device solve is deterministic";
  }
}

TEST_F(FemDeviceTest, StaticSolveOnTheDeviceIsJacobiPreconditionedOnly) {
  const StaticProblem p = grabbed_cube(FemLaw::linear);
  FemStaticOptions o;
  o.preconditioner = FemPreconditioner::incomplete_cholesky;
  try {
    solve_fem_static(p.model, p.bc, {}, o, Backend::cuda);
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "preconditioner");
  }
}

}  // namespace
}  // namespace ctsurg::sim
