// CPU vs GPU agreement of DeviceSimulation (label gpu): every test skips, naming the reason, on a
// machine without a CUDA device, and runs with one (bench/gpu/run.sh runs them, also under
// compute-sanitizer).
//
// Tolerances. The device kernels are the CPU's per-index functions, compiled without FMA contraction
// on both sides (-fmad=false, -ffp-contract=off), with IEEE division and square root (nvcc's default
// -prec-div, -prec-sqrt) and no flush to zero; each particle sums its springs in the same order. One
// step is therefore expected to give the same bits; the test allows 4 float ulps of the largest
// coordinate (kOneStepUlps). Over 1,000 steps rounding differences, if any appeared, could grow with
// the dynamics (an undamped perturbed block: a chaotic system), so the run is checked to 1e-3 mm,
// 0.05% of the 2 mm cell (kRunTolerance).
#include "ctsurg/sim/springs/device_simulation.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/springs/explicit_spring_model.h"
#include "ctsurg/sim/springs/sphere_tools.h"
#include "ctsurg/sim/springs/spring_cutting.h"
#include "ctsurg/sim/springs/spring_mass_step.h"
#include "ctsurg/sim/springs/stability.h"
#include "ctsurg/sim/surface/surface_coupling.h"
#include "sim_test_models.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <string>

namespace ctsurg::sim {
namespace {

constexpr double kOneStepUlps = 4;
constexpr double kRunTolerance = 1e-3;  // mm

class DeviceSimulationTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!cuda_built()) GTEST_SKIP() << "this build has no CUDA (CTSURG_CUDA=OFF or no nvcc)";
    if (cuda_device_count() == 0) GTEST_SKIP() << "no CUDA device on this machine";
  }
};

double max_abs_difference(const std::vector<Real>& a, const std::vector<Real>& b) {
  EXPECT_EQ(a.size(), b.size());
  double m = 0;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) m = std::max(m, std::abs(double(a[i]) - b[i]));
  return m;
}

double max_position_difference(const ParticleState& a, const ParticleState& b) {
  return std::max({max_abs_difference(a.x, b.x), max_abs_difference(a.y, b.y), max_abs_difference(a.z, b.z),
                   max_abs_difference(a.px, b.px), max_abs_difference(a.py, b.py), max_abs_difference(a.pz, b.pz)});
}

double max_magnitude(const ParticleState& s) {
  double m = 0;
  for (int32_t i = 0; i < s.count(); ++i) m = std::max({m, std::abs(double(s.x[i])), std::abs(double(s.y[i])), std::abs(double(s.z[i]))});
  return m;
}

double ulps_tolerance(const ParticleState& s) {
  return kOneStepUlps * std::numeric_limits<Real>::epsilon() * max_magnitude(s);
}

// A holed block (both of the CPU kernel's paths), perturbed, a few particles fixed, with gravity.
SpringGridModel test_grid(double damping) {
  return build_spring_grid_model(test::holed_block_occupancy(13, 11, 9, 2.0), test::test_material(1000, 500, damping));
}

ParticleState test_state(const SpringGridModel& model) {
  auto s = model.make_state();
  test::perturb(s, 0.2);
  for (int32_t i = 0; i < s.count(); i += 37) s.set_fixed(i, true);
  return s;
}

StepParameters test_parameters(const SpringGridModel& model) {
  StepParameters p;
  p.dt = critical_time_step(model).dt;
  p.damping = 0.001;
  p.gravity = {0, 0, -9810};
  return p;
}

template <class Model>
void expect_steps_agree(const Model& model, ParticleState cpu, const StepParameters& p, int steps, double tolerance) {
  DeviceSimulation gpu;
  gpu.upload(model, cpu);
  for (int k = 0; k < steps; ++k) step(model, cpu, p);
  gpu.step(steps, p);
  ParticleState back;
  gpu.download_state(back);
  EXPECT_LE(max_position_difference(cpu, back), tolerance) << steps << " steps";
}

TEST_F(DeviceSimulationTest, ReportsTheDevice) {
  DeviceSimulation gpu;
  const DeviceInfo info = gpu.device_info();
  EXPECT_FALSE(info.name.empty());
  EXPECT_GT(info.total_bytes, 0);
  EXPECT_GT(info.multiprocessors, 0);
  std::cout << "device " << info.ordinal << ": " << info.name << ", sm_" << info.compute_major << info.compute_minor
            << ", " << info.total_bytes / (1 << 20) << " MiB, peak " << info.peak_bandwidth_gbs << " GB/s\n";
}

TEST_F(DeviceSimulationTest, GridOneStepMatchesTheCpuToAFewUlps) {
  for (double damping : {0.0, 5.0}) {
    const auto model = test_grid(damping);
    const auto s = test_state(model);
    expect_steps_agree(model, s, test_parameters(model), 1, ulps_tolerance(s));
  }
}

TEST_F(DeviceSimulationTest, GridThousandStepsMatchTheCpu) {
  for (double damping : {0.0, 5.0}) {
    const auto model = test_grid(damping);
    expect_steps_agree(model, test_state(model), test_parameters(model), 1000, kRunTolerance);
  }
}

TEST_F(DeviceSimulationTest, ExplicitStepsMatchTheCpu) {
  for (double damping : {0.0, 5.0}) {
    const auto grid = test_grid(damping);
    const auto model = explicit_model_from_grid(grid);
    const auto s = test_state(grid);
    expect_steps_agree(model, s, test_parameters(grid), 1, ulps_tolerance(s));
    expect_steps_agree(model, s, test_parameters(grid), 1000, kRunTolerance);
  }
}

TEST_F(DeviceSimulationTest, StepsSplitAcrossCallsAndGraphsGiveTheSameResult) {
  const auto model = test_grid(5.0);
  const auto s = test_state(model);
  const auto p = test_parameters(model);
  DeviceSimulation a, b;
  a.upload(model, s), b.upload(model, s);
  a.step(301, p);
  for (int64_t n : {1, 2, 97, 48, 144, 9}) b.step(n, p);  // 301 in pieces: direct launches and replays
  ParticleState sa, sb;
  a.download_state(sa), b.download_state(sb);
  EXPECT_EQ(max_position_difference(sa, sb), 0.0);
}

TEST_F(DeviceSimulationTest, NormalsMatchTheCpu) {
  const auto model = test_grid(0.0);
  auto cpu = test_state(model);
  const auto p = test_parameters(model);
  DeviceSimulation gpu;
  gpu.upload(model, cpu);
  ParticleNormals expected;
  step(model, cpu, p, &expected);
  const ParticleNormals got = gpu.normals(p);
  EXPECT_LE(max_abs_difference(expected.x, got.x), 1e-6);
  EXPECT_LE(max_abs_difference(expected.y, got.y), 1e-6);
  EXPECT_LE(max_abs_difference(expected.z, got.z), 1e-6);
}

TEST_F(DeviceSimulationTest, ProbeMovesTheSameParticlesToTheSamePlaces) {
  const auto model = test_grid(0.0);
  auto cpu = test_state(model);
  DeviceSimulation gpu;
  gpu.upload(model, cpu);
  const Sphere tool{{10 + 2 * 6.5, -20 + 2 * 5.5, 30 + 2 * 4.5}, 5.0};  // inside the block
  const int64_t moved_cpu = probe_sphere(cpu, tool);
  const int64_t moved_gpu = gpu.probe(tool);
  EXPECT_GT(moved_cpu, 0);
  EXPECT_EQ(moved_gpu, moved_cpu);
  ParticleState back;
  gpu.download_state(back);
  EXPECT_EQ(max_position_difference(cpu, back), 0.0);
}

TEST_F(DeviceSimulationTest, GrabCapturesTheSameSetAndHoldsItThroughSteps) {
  const auto model = test_grid(5.0);
  auto cpu = test_state(model);
  const auto p = test_parameters(model);
  DeviceSimulation gpu;
  gpu.upload(model, cpu);
  const Sphere tool{{10 + 2 * 3.5, -20 + 2 * 5.5, 30 + 2 * 4.5}, 4.0};
  const Grab expected = grab_particles_in_sphere(cpu, tool);
  const Grab got = gpu.grab(tool);
  ASSERT_FALSE(expected.particles.empty());
  EXPECT_EQ(got.particles, expected.particles);
  EXPECT_EQ(got.offsets, expected.offsets);
  EXPECT_TRUE(gpu.grab_held());
  // The CPU loop of a scenario: step, then place the grab at the tool's centre of that time.
  std::array<double, 3> centre = tool.centre;
  for (int k = 0; k < 100; ++k) {
    centre[0] += 0.01;
    step(model, cpu, p);
    apply_grab(cpu, expected, centre);
    gpu.step(1, p);
    gpu.apply_grab(centre);
  }
  ParticleState back;
  gpu.download_state(back);
  EXPECT_LE(max_position_difference(cpu, back), kRunTolerance);
  // Many steps per call with the grab held at a fixed centre (graph replays with the grab kernel).
  for (int k = 0; k < 200; ++k) {
    step(model, cpu, p);
    apply_grab(cpu, expected, centre);
  }
  gpu.step(200, p);
  gpu.download_state(back);
  EXPECT_LE(max_position_difference(cpu, back), kRunTolerance);
  gpu.release_grab();
  EXPECT_FALSE(gpu.grab_held());
  EXPECT_THROW(gpu.apply_grab(centre), InputError);
}

Triangle test_blade() {
  // A vertical triangle through the block's middle, crossing many springs.
  return {{10 + 13.1, -30, 20}, {10 + 13.1, 30, 20}, {10 + 13.1, 0, 80}};
}

TEST_F(DeviceSimulationTest, GridCutRemovesTheSameSprings) {
  auto cpu_model = test_grid(0.0);
  auto gpu_model = cpu_model;
  const auto s = test_state(cpu_model);
  DeviceSimulation gpu;
  gpu.upload(gpu_model, s);
  const int64_t cut_cpu = cut_springs_crossing_triangle(cpu_model, s, test_blade());
  const int64_t cut_gpu = gpu.cut_springs_crossing_triangle(test_blade());
  EXPECT_GT(cut_cpu, 0);
  EXPECT_EQ(cut_gpu, cut_cpu);
  gpu.download_springs(gpu_model);
  EXPECT_EQ(gpu_model.spring_mask, cpu_model.spring_mask);
  // And the cut model steps alike.
  auto cpu = s;
  const auto p = test_parameters(cpu_model);
  for (int k = 0; k < 100; ++k) step(cpu_model, cpu, p);
  gpu.step(100, p);
  ParticleState back;
  gpu.download_state(back);
  EXPECT_LE(max_position_difference(cpu, back), kRunTolerance);
}

TEST_F(DeviceSimulationTest, ExplicitCutRemovesTheSameSprings) {
  const auto grid = test_grid(0.0);
  auto cpu_model = explicit_model_from_grid(grid);
  auto gpu_model = cpu_model;
  const auto s = test_state(grid);
  DeviceSimulation gpu;
  gpu.upload(gpu_model, s);
  const int64_t cut_cpu = cut_springs_crossing_triangle(cpu_model, s, test_blade());
  EXPECT_GT(cut_cpu, 0);
  EXPECT_EQ(gpu.cut_springs_crossing_triangle(test_blade()), cut_cpu);
  gpu.download_springs(gpu_model);
  EXPECT_EQ(gpu_model.alive, cpu_model.alive);
  EXPECT_EQ(gpu_model.ell_present, cpu_model.ell_present);
}

// A coupling built by hand: each vertex follows up to 8 particles with weights summing to 1.
SurfaceCoupling test_coupling(int32_t particles, int64_t vertices) {
  SurfaceCoupling c;
  c.particles.assign(static_cast<std::size_t>(8 * vertices), -1);
  c.weights.assign(static_cast<std::size_t>(8 * vertices), 0);
  for (int64_t v = 0; v < vertices; ++v) {
    const int corners = 1 + static_cast<int>(v % 8);
    for (int k = 0; k < corners; ++k) {
      c.particles[static_cast<std::size_t>(8 * v + k)] = static_cast<int32_t>((v * 131 + k * 17) % particles);
      c.weights[static_cast<std::size_t>(8 * v + k)] = Real(1) / static_cast<Real>(corners);
    }
    for (int a = 0; a < 3; ++a) c.rest_vertices.push_back(static_cast<Real>(0.1 * v + a));
  }
  return c;
}

TEST_F(DeviceSimulationTest, SurfaceFramesMatchTheCpuAndComeBackAsynchronously) {
  const auto model = test_grid(5.0);
  auto cpu = test_state(model);
  const auto p = test_parameters(model);
  const SurfaceCoupling coupling = test_coupling(model.particle_count(), 5000);
  DeviceSimulation gpu;
  gpu.upload(model, cpu);
  gpu.set_surface(coupling, model.rest_positions);
  std::vector<float> expected;
  for (int frame = 0; frame < 4; ++frame) {
    for (int k = 0; k < 50; ++k) step(model, cpu, p);
    move_surface(coupling, cpu, model.rest_positions, expected);
    gpu.step(50, p);
    gpu.move_surface_async();
    if (frame % 2 == 1) continue;  // two frames in flight: wait for every second one only
    const std::span<const float> got = gpu.wait_surface();
    ASSERT_EQ(got.size(), expected.size());
    double m = 0;
    for (std::size_t i = 0; i < got.size(); ++i) m = std::max(m, std::abs(double(got[i]) - expected[i]));
    EXPECT_LE(m, kRunTolerance) << "frame " << frame;
  }
  const std::span<const float> last = gpu.wait_surface();
  ASSERT_EQ(last.size(), expected.size());
  double m = 0;
  for (std::size_t i = 0; i < last.size(); ++i) m = std::max(m, std::abs(double(last[i]) - expected[i]));
  EXPECT_LE(m, kRunTolerance);
}

TEST_F(DeviceSimulationTest, ChecksArgumentsOnTheHost) {
  const auto model = test_grid(0.0);
  DeviceSimulation gpu;
  StepParameters p;
  p.dt = 1e-4;
  EXPECT_THROW(gpu.step(1, p), InputError);  // no model yet
  auto s = model.make_state();
  gpu.upload(model, s);
  EXPECT_THROW(gpu.step(-1, p), InputError);
  p.dt = 0;
  EXPECT_THROW(gpu.step(1, p), InputError);
  EXPECT_THROW(gpu.probe({{0, 0, 0}, -1}), InputError);
  EXPECT_THROW(gpu.move_surface_async(), InputError);
  EXPECT_THROW(DeviceSimulation{cuda_device_count()}, InputError);
  s.x.pop_back();
  EXPECT_THROW(gpu.upload(model, s), InputError);
}

}  // namespace
}  // namespace ctsurg::sim
