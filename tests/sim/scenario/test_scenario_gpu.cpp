// The scenario runner on a CUDA device (label gpu; skipped without one): the same scenario on the cpu
// and cuda backends gives the same trajectory to float rounding (the kernels are the same source,
// compiled without FMA contraction on both sides), including a grab, a probe and a cut, and two grabs
// held together and released at different times (heart_cut's retractors); a scenario the device
// cannot run (a force tool) is refused before it starts.
#include "ctsurg/core/error.h"
#include "ctsurg/core/occupancy_grid_file.h"
#include "ctsurg/core/surface_mesh_file.h"
#include "ctsurg/mesh/lattice_padding.h"
#include "ctsurg/mesh/marching_cubes.h"
#include "ctsurg/sim/base/backend.h"
#include "ctsurg/sim/scenario/scenario.h"
#include "ctsurg/sim/scenario/scenario_run.h"
#include "scenario_test_files.h"
#include "sim_test_models.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>

namespace fs = std::filesystem;
using namespace ctsurg;
using namespace ctsurg::sim;

namespace {

void write_block(const fs::path& dir) { ctsurg::sim::test::write_block_files(dir, 16, 6, 6, 2.0); }

// The largest |a_i - b_i| (mm) of two trajectories' vertex arrays of one size.
double largest_difference(const std::vector<float>& a, const std::vector<float>& b) {
  double worst = 0;
  for (size_t i = 0; i < a.size(); ++i) worst = std::max(worst, std::abs(double(a[i]) - b[i]));
  return worst;
}

// Each frame's largest difference (mm), for the failure message: where the two runs part.
std::string frame_differences(const Trajectory& a, const Trajectory& b) {
  std::string text;
  for (int64_t f = 0; f < a.frame_count() && f < b.frame_count(); ++f) {
    double worst = 0;
    const float *x = a.frame_vertices(f), *y = b.frame_vertices(f);
    for (int64_t i = 0; i < 3 * a.vertex_count(); ++i) worst = std::max(worst, std::abs(double(x[i]) - y[i]));
    char item[64];
    std::snprintf(item, sizeof item, "t %.3f: %.3g mm; ", a.time[static_cast<size_t>(f)], worst);
    text += item;
  }
  return text;
}

const char* kScenario = R"(ctsurg_scenario: 1
model: {kind: spring_grid, grid: grid.h5, surface: surface.h5}
material: {preset: liver, damping_per_s: 20}
fixed: [{box_fraction: {min: [0, 0, 0], max: [0.05, 1, 1]}}]
tools:
  - grab: {radius_mm: 3, snap_to_tissue: true, path: [{t: 0, at_fraction: [1, 0.5, 0.5]}, {t: 0.05, offset_mm: [0, 0, 6]}]}
  - probe: {radius_mm: 3, path: [{t: 0, position_mm: [26, -15, 46]}, {t: 0.08, position_mm: [26, -15, 40]}]}
  - cut: {blade_edge_mm: [0, 0, 30], path: [{t: 0.02, position_mm: [19, -30, 36]}, {t: 0.06, position_mm: [19, 0, 36]}]}
time: {duration_s: 0.1}
output: {trajectory: out.h5, frame_interval_s: 0.01}
)";

}  // namespace

TEST(ScenarioGpu, CpuAndCudaGiveTheSameTrajectory) {
  if (!backend_available(Backend::cuda)) GTEST_SKIP() << "no CUDA device (or a build without CUDA)";
  ctsurg::test::TempDir dir;
  write_block(dir.path());
  auto s = parse_scenario(kScenario, dir.path() / "s.yaml", dir.path());
  s.backend = "cpu";
  RunReport rc, rg;
  const Trajectory c = run_scenario(s, &rc);
  s.backend = "cuda";
  const Trajectory g = run_scenario(s, &rg);
  EXPECT_EQ(rc.springs_cut, rg.springs_cut);
  EXPECT_EQ(c.topologies, g.topologies);
  ASSERT_EQ(c.vertices.size(), g.vertices.size());
  const double worst = largest_difference(c.vertices, g.vertices);
  EXPECT_LT(worst, 1e-3) << frame_differences(c, g);  // mm after 0.1 s
}

TEST(ScenarioGpu, TwoGrabsHeldTogetherMatchTheCpu) {
  if (!backend_available(Backend::cuda)) GTEST_SKIP() << "no CUDA device (or a build without CUDA)";
  ctsurg::test::TempDir dir;
  write_block(dir.path());
  const char* two = R"(ctsurg_scenario: 1
model: {kind: spring_grid, grid: grid.h5, surface: surface.h5}
material: {preset: liver, damping_per_s: 20}
fixed: [{box_fraction: {min: [0, 0, 0], max: [0.05, 1, 1]}}]
tools:
  - grab: {radius_mm: 3, snap_to_tissue: true, end_s: 0.07, path: [{t: 0, at_fraction: [1, 0.5, 0.5]}, {t: 0.05, offset_mm: [0, 0, 6]}]}
  - grab: {radius_mm: 3, snap_to_tissue: true, start_s: 0.02, path: [{t: 0.02, at_fraction: [0.6, 0, 0.5]}, {t: 0.06, offset_mm: [0, -4, 0]}]}
time: {duration_s: 0.1}
output: {trajectory: out.h5, frame_interval_s: 0.01}
)";
  auto s = parse_scenario(two, dir.path() / "s.yaml", dir.path());
  s.backend = "cpu";
  const Trajectory c = run_scenario(s);
  s.backend = "cuda";
  const Trajectory g = run_scenario(s);
  ASSERT_EQ(c.vertices.size(), g.vertices.size());
  const double worst = largest_difference(c.vertices, g.vertices);
  EXPECT_LT(worst, 1e-3) << frame_differences(c, g);  // mm after 0.1 s
}

TEST(ScenarioGpu, WhatTheDeviceCannotRunIsRefused) {
  if (!backend_available(Backend::cuda)) GTEST_SKIP() << "no CUDA device (or a build without CUDA)";
  ctsurg::test::TempDir dir;
  write_block(dir.path());
  std::string text = kScenario;
  text += "backend: cuda\n";  // (operator+ here trips GCC 12's -Warray-bounds false positive)
  auto s = parse_scenario(text, dir.path() / "s.yaml", dir.path());
  ToolAction force = s.tools[0];
  force.type = find_tool_type("force");
  force.force_n = {0, 0, 0.01};
  force.label = "tools[3] (force)";
  s.tools.push_back(force);
  try {
    (void)run_scenario(s);
    ADD_FAILURE() << "a force tool was accepted on cuda";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "tools[3] (force)");
  }
}

// An FEM scenario with a surface on the device (heart_fem_grab's shape: static Neo-Hookean, a grab, the
// surface embedded in the tets): its frames come from the host, and match the CPU's (the device runs the
// conjugate gradients only).
TEST(ScenarioGpu, FemScenarioWithASurfaceMatchesTheCpu) {
  if (!backend_available(Backend::cuda)) GTEST_SKIP() << "no CUDA device (or a build without CUDA)";
  ctsurg::test::TempDir dir;
  ctsurg::sim::test::write_block_files(dir.path(), 16, 4, 4, 2.0);
  ctsurg::sim::test::write_bar_tet_mesh(dir.path());
  const char* fem = R"(ctsurg_scenario: 1
model: {kind: fem, tetmesh: tetmesh.h5, surface: surface.h5, solver: static}
material: {law: neo_hookean, preset: liver}
fixed: [{box_fraction: {min: [0, 0, 0], max: [0.05, 1, 1]}}]
tools:
  - grab: {radius_mm: 3, snap_to_tissue: true, path: [{t: 0, at_fraction: [1, 0.5, 0.5]}, {t: 0.1, offset_mm: [0, 0, 5]}]}
time: {duration_s: 0.1}
output: {trajectory: out.h5, frame_interval_s: 0.025}
)";
  auto s = parse_scenario(fem, dir.path() / "s.yaml", dir.path());
  s.backend = "cpu";
  const Trajectory c = run_scenario(s);
  s.backend = "cuda";
  const Trajectory g = run_scenario(s);
  ASSERT_EQ(c.vertices.size(), g.vertices.size());
  const double worst = largest_difference(c.vertices, g.vertices);
  EXPECT_LT(worst, 1e-3);  // mm: both solve each frame to the same tolerance
}
