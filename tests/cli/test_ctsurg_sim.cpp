// ctsurg-sim as a user runs it: a grid file and its surface from ctsurg-surface, a scenario file next
// to them, the trajectory (+ XDMF) it writes, byte-identical reruns, and bad input: a misspelt key, an
// input that is missing, a CUDA request in a CPU build (exit 2, the file and field named, nothing
// written), an unstable step (exit 1, a message with a step to try, an existing output left as it was).
#include "ctsurg/core/occupancy_grid_file.h"
#include "ctsurg/core/trajectory_file.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <hdf5.h>

#include <cmath>
#include <fstream>

namespace fs = std::filesystem;
using ctsurg::test::read_bytes;
using ctsurg::test::run_tool;
using ctsurg::test::TempDir;

namespace {

// A 12 x 4 x 4 bar of 2 mm cells and its surface, written into `dir` as grid.h5 and surface.h5.
void write_inputs(const fs::path& dir) {
  ctsurg::ImageGeometry g;
  g.dims = {14, 6, 6};
  g.spacing = Eigen::Vector3d::Constant(2.0);
  g.origin = Eigen::Vector3d(-10, 40, 100);
  ctsurg::OccupancyGrid grid;
  grid.occupancy = ctsurg::Volume<uint8_t>(g, 0);
  grid.fraction = ctsurg::Volume<float>(g, 0.f);
  grid.label = ctsurg::Volume<uint16_t>(g, 0);
  for (int k = 1; k < 5; ++k)
    for (int j = 1; j < 5; ++j)
      for (int i = 1; i < 13; ++i) {
        grid.occupancy(i, j, k) = 1;
        grid.fraction(i, j, k) = 1.f;
        grid.label(i, j, k) = 1;
      }
  grid.mask = grid.label;
  grid.label_names = {{1, "bar"}};
  ctsurg::write_occupancy_grid_file(dir / "grid.h5", grid, ctsurg::test::test_provenance());
  const auto r = run_tool("ctsurg-surface", {(dir / "grid.h5").string(), (dir / "surface.h5").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
}

std::string scenario(const std::string& material = "  preset: liver\n", const std::string& time = "  dt_s: auto\n") {
  return "ctsurg_scenario: 1\nname: bar pull\nmodel:\n  kind: spring_grid\n  grid: grid.h5\n  surface: surface.h5\n"
         "material:\n" + material +
         "  damping_per_s: 20\nfixed:\n  - box_fraction: {min: [0, 0, 0], max: [0.05, 1, 1]}\n"
         "tools:\n  - grab:\n      radius_mm: 3\n      snap_to_tissue: true\n      path:\n"
         "        - {t: 0, at_fraction: [1, 0.5, 0.5]}\n        - {t: 0.05, offset_mm: [0, 0, 5]}\n"
         "time:\n  duration_s: 0.1\n" + time + "output:\n  trajectory: out/traj.h5\n  frame_interval_s: 0.01\n";
}

void write_text(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }

}  // namespace

TEST(CtsurgSim, RunsAScenarioAndWritesATrajectory) {
  TempDir dir;
  write_inputs(dir.path());
  fs::create_directory(dir.path() / "out");
  write_text(dir.path() / "s.yaml", scenario());
  const auto r = run_tool("ctsurg-sim", {(dir.path() / "s.yaml").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("grabbed"), std::string::npos) << r.output;
  const fs::path out = dir.path() / "out" / "traj.h5";
  ASSERT_TRUE(fs::exists(out));
  EXPECT_TRUE(fs::exists(dir.path() / "out" / "traj.xdmf"));
  const ctsurg::Trajectory t = ctsurg::read_trajectory_file(out);
  EXPECT_EQ(t.scenario, "bar pull");
  EXPECT_EQ(t.frame_count(), 11);
  EXPECT_NEAR(t.metric("max_displacement")->values.back(), 5.0, 0.3);
  EXPECT_EQ(t.surface_sha256.size(), 64u);
  // Deterministic: a rerun into another file gives the same trajectory bytes (provenance aside, it
  // names the output) and the same frames.
  const auto r2 = run_tool("ctsurg-sim", {(dir.path() / "s.yaml").string(), "-o", (dir.path() / "again.h5").string(), "-q"});
  ASSERT_EQ(r2.exit_code, 0) << r2.output;
  EXPECT_EQ(ctsurg::read_trajectory_file(dir.path() / "again.h5").vertices, t.vertices);
}

TEST(CtsurgSim, BadInputIsExitTwoWithTheFieldNamedAndNothingWritten) {
  TempDir dir;
  write_inputs(dir.path());
  fs::create_directory(dir.path() / "out");
  const fs::path out = dir.path() / "out" / "traj.h5";
  struct Case {
    std::string text;
    std::vector<std::string> extra;
    std::string expected;
  };
  const Case cases[] = {
      {scenario("  preset: liver\n  youngs_modulus: 5000\n"), {}, "s.yaml: material.youngs_modulus: unknown key"},
      {scenario(), {"--grid", (dir.path() / "nothing.h5").string()}, "nothing.h5"},
      {scenario(), {"--backend", "cuda"}, "cuda"},
      {scenario(), {"-o", (dir.path() / "out" / "traj.vtk").string()}, "output.trajectory"},
      // Issue 17: E = 1e300 gave "stability: dt: must be > 0", naming no field.
      {scenario("  youngs_modulus_pa: 1e300\n"), {}, "s.yaml: material.youngs_modulus_pa: must be from 1 Pa to 1e11 Pa"},
      // Issue 17: duration_s 1e9 or dt_s 1e-12 ran until killed.
      {scenario("  preset: liver\n", "  dt_s: 1e-12\n"), {}, "time.dt_s: must be at least"},
      {scenario("  preset: liver\n", "").replace(scenario().find("duration_s: 0.1"), 15, "duration_s: 1e9"), {},
       "time.duration_s: must be at most"},
      // Issue 17: an output that is an input replaced it.
      {scenario(), {"-o", (dir.path() / "grid.h5").string()}, "is the input"},
      {scenario(), {"-o", (dir.path() / "surface.h5").string()}, "is the input"},
  };
  for (const auto& c : cases) {
    write_text(dir.path() / "s.yaml", c.text);
    std::vector<std::string> args{(dir.path() / "s.yaml").string()};
    args.insert(args.end(), c.extra.begin(), c.extra.end());
    const auto r = run_tool("ctsurg-sim", args);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(c.expected), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out));
    EXPECT_FALSE(fs::exists(dir.path() / "out" / "traj.vtk"));
  }
}

TEST(CtsurgSim, UnstableRunStopsWithAStepToTryAndKeepsTheOldOutput) {
  TempDir dir;
  write_inputs(dir.path());
  fs::create_directory(dir.path() / "out");
  const fs::path out = dir.path() / "out" / "traj.h5";
  write_text(out, "an earlier result");
  write_text(dir.path() / "s.yaml", scenario("  preset: myocardium\n", "  dt_s: 0.004\n"));
  const auto r = run_tool("ctsurg-sim", {(dir.path() / "s.yaml").string()});
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("unstable"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("dt <="), std::string::npos) << r.output;
  EXPECT_EQ(read_bytes(out), "an earlier result");
}

// Issue 17: ctsurg-sim checked its output folder only after simulating (40 s lost on a read-only
// folder). The output is checked before the run starts: the run's report never appears.
TEST(CtsurgSim, TheOutputIsCheckedBeforeSimulating) {
  TempDir dir;
  write_inputs(dir.path());
  write_text(dir.path() / "s.yaml", scenario());
  for (const fs::path& out : {dir.path() / "absent" / "traj.h5", dir.path() / "s.yaml"}) {
    const auto r = run_tool("ctsurg-sim", {(dir.path() / "s.yaml").string(), "-o", out.string()});
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(out.string()), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("steps in"), std::string::npos) << "it simulated first:\n" << r.output;
  }
}

// Issue 17: a run that would take hours ran with no estimate. After its first second the run is
// estimated; over an hour it asks for --force (exit 2, naming the estimate and the limit).
TEST(CtsurgSim, ARunEstimatedToTakeTooLongAsksForForce) {
  TempDir dir;
  write_inputs(dir.path());
  fs::create_directory(dir.path() / "out");
  std::string text = scenario("  preset: liver\n", "  dt_s: 1e-6\n");
  text.replace(text.find("duration_s: 0.1"), 15, "duration_s: 80000");
  text.replace(text.find("frame_interval_s: 0.01"), 22, "frame_interval_s: 1000");
  write_text(dir.path() / "s.yaml", text);
  const auto r = run_tool("ctsurg-sim", {(dir.path() / "s.yaml").string()});
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("time.duration_s: this run would take about"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--force"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir.path() / "out" / "traj.h5"));
}

// Issue 17: a NaN surface vertex gave a NaN trajectory (docs/sim.md promises never). The surface is
// refused where it enters, naming the dataset.
TEST(CtsurgSim, ANanSurfaceVertexIsRefusedWhereItEnters) {
  TempDir dir;
  write_inputs(dir.path());
  fs::create_directory(dir.path() / "out");
  {
    const hid_t file = H5Fopen((dir.path() / "surface.h5").c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    const hid_t ds = H5Dopen2(file, "/surface/vertices", H5P_DEFAULT);
    const hid_t space = H5Dget_space(ds);
    std::vector<float> v(static_cast<std::size_t>(H5Sget_simple_extent_npoints(space)));
    ASSERT_GE(H5Dread(ds, H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), 0);
    v[7] = std::nanf("");
    ASSERT_GE(H5Dwrite(ds, H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), 0);
    H5Sclose(space);
    H5Dclose(ds);
    H5Fclose(file);
  }
  write_text(dir.path() / "s.yaml", scenario());
  const auto r = run_tool("ctsurg-sim", {(dir.path() / "s.yaml").string()});
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("/surface/vertices: NaN at row 2, column 1"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir.path() / "out" / "traj.h5"));
}
