// Tests for ctsurg/sim/scenario/scenario.h: a full scenario parses into the documented fields
// (presets, overrides, regions, tools, paths resolved against the file's folder); JSON works; every
// kind of mistake is an InputError naming the file and the field.
#include "ctsurg/sim/scenario/scenario.h"
#include "ctsurg/sim/scenario/scenario_model.h"

#include "ctsurg/core/error.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <set>

namespace fs = std::filesystem;
using ctsurg::sim::parse_scenario;

namespace {

// What parse_scenario says of `text` (read as /b/f.yaml): the InputError's message, or "(accepted)".
std::string parse_error(const std::string& text) {
  try {
    (void)parse_scenario(text, "f.yaml", "/b");
  } catch (const ctsurg::InputError& e) {
    return e.what();
  }
  return "(accepted)";
}

// parse_error(text) names `part` (a file, a field, a problem).
void expect_error(const std::string& text, const std::string& part) {
  const std::string e = parse_error(text);
  EXPECT_NE(e.find(part), std::string::npos) << e;
}

const char* kFull = R"(
ctsurg_scenario: 1
name: grab test
model:
  kind: spring_grid
  grid: grid.h5
  surface: out/surface.h5
  coupling: nearest_particle
material:
  preset: liver
  youngs_modulus_pa: 8000
  damping_per_s: 20
gravity_mm_per_s2: [0, 0, -9810]
fixed:
  - box_fraction: {min: [0, 0, 0], max: [1, 1, 0.2]}
  - half_space: {point_mm: [0, 0, 10], normal: [0, 0, 1]}
  - label: 2
tools:
  - grab:
      radius_mm: 5
      start_s: 0.1
      end_s: 0.5
      snap_to_tissue: true
      path:
        - {t: 0.1, at_fraction: [0.5, 0.0, 0.5]}
        - {t: 0.4, offset_mm: [0, -10, 0]}
  - cut:
      blade_edge_mm: [0, 0, 20]
      path:
        - {t: 0.2, position_mm: [1, 2, 3]}
        - {t: 0.3, position_mm: [11, 2, 3]}
time:
  duration_s: 0.6
  dt_s: auto
  max_step_halvings: 2
output:
  trajectory: traj.h5
  frame_interval_s: 0.02
)";

std::string error_of(const std::string& text) {
  try {
    (void)parse_scenario(text, "s.yaml", "/base");
  } catch (const ctsurg::InputError& e) {
    return e.what();
  }
  return "(accepted)";
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

}  // namespace

TEST(Scenario, FullScenarioParsesEveryField) {
  const auto s = parse_scenario(kFull, "dir/s.yaml", "/base");
  EXPECT_EQ(s.name, "grab test");
  EXPECT_EQ(s.model, ctsurg::sim::ModelKind::spring_grid);
  EXPECT_EQ(s.grid, fs::path("/base/grid.h5"));
  EXPECT_EQ(s.surface, fs::path("/base/out/surface.h5"));
  EXPECT_EQ(s.coupling, ctsurg::sim::CouplingMode::nearest_particle);
  EXPECT_EQ(s.material.youngs_modulus_pa, 8000);  // the override
  EXPECT_EQ(s.material.poisson_ratio, 0.45);      // from the preset
  EXPECT_NEAR(s.material.density, 1.06e-3, 1e-12);
  EXPECT_EQ(s.damping_per_s, 20);
  EXPECT_EQ(s.gravity[2], -9810);
  ASSERT_EQ(s.fixed.size(), 3u);
  EXPECT_EQ(s.fixed[0].kind, ctsurg::sim::FixedRegionSpec::Kind::box_fraction);
  EXPECT_EQ(s.fixed[0].box.max[2], 0.2);
  EXPECT_EQ(s.fixed[1].half_space.point[2], 10);
  EXPECT_EQ(s.fixed[2].label, 2);
  ASSERT_EQ(s.tools.size(), 2u);
  EXPECT_STREQ(s.tools[0].kind(), "grab");
  EXPECT_EQ(s.tools[0].radius_mm, 5);
  EXPECT_EQ(s.tools[0].end_s, 0.5);
  EXPECT_TRUE(s.tools[0].snap_to_tissue);
  ASSERT_EQ(s.tools[0].path.size(), 2u);
  EXPECT_EQ(s.tools[0].path[1].point.kind, ctsurg::sim::PointSpec::Kind::offset_mm);
  EXPECT_STREQ(s.tools[1].kind(), "cut");
  EXPECT_EQ(s.tools[1].start_s, 0.2);  // defaults to the first keyframe
  EXPECT_TRUE(std::isinf(s.tools[1].end_s));
  EXPECT_EQ(s.tools[1].blade_edge_mm[2], 20);
  EXPECT_EQ(s.duration_s, 0.6);
  EXPECT_EQ(s.dt_s, 0);  // auto
  EXPECT_EQ(s.max_step_halvings, 2);
  EXPECT_EQ(s.trajectory, fs::path("/base/traj.h5"));
  EXPECT_EQ(s.frame_interval_s, 0.02);
}

TEST(Scenario, JsonIsAccepted) {
  const auto s = parse_scenario(
      R"({"ctsurg_scenario": 1, "model": {"kind": "explicit_springs", "grid": "g.h5", "springs_from": "tetmesh",
          "tetmesh": "t.h5"}, "material": {"preset": "kidney"}, "time": {"duration_s": 1, "dt_s": 1e-4},
          "output": {"trajectory": "o.h5"}})",
      "s.json", "/b");
  EXPECT_EQ(s.model, ctsurg::sim::ModelKind::explicit_springs);
  EXPECT_EQ(s.springs_from, ctsurg::sim::SpringSource::tetmesh);
  EXPECT_EQ(s.tetmesh, fs::path("/b/t.h5"));
  EXPECT_EQ(s.material.youngs_modulus_pa, 10e3);
  EXPECT_EQ(s.dt_s, 1e-4);
  EXPECT_EQ(s.name, "s");
  EXPECT_NEAR(s.frame_interval_s, 0.02, 1e-15);  // 50 frames by default
}

TEST(Scenario, MistakesNameTheFileAndTheField) {
  struct Case {
    std::string from, to, expected;
  };
  const Case cases[] = {
      {"kind: spring_grid", "kind: springs", "s.yaml: model.kind: 'springs' is not one of"},
      {"  preset: liver", "  preset: spleen", "s.yaml: material.preset: unknown material preset 'spleen' (known: myocardium"},
      {"youngs_modulus_pa: 8000", "youngs_modulus_pa: -3", "material.youngs_modulus_pa: must be > 0"},
      {"damping_per_s: 20", "damping_per_s: 20\n  poisson_ratio: 0.5", "material.poisson_ratio: must be in (-1, 0.5)"},
      {"duration_s: 0.6", "duration_s: soon", "time.duration_s: expected a number, got 'soon'"},
      {"radius_mm: 5", "radius_mm: 0", "tools[0].grab.radius_mm: must be > 0"},
      {"{t: 0.4, offset_mm", "{t: 0.05, offset_mm", "tools[0].grab.path[1].t: keyframe times must increase"},
      {"{t: 0.1, at_fraction: [0.5, 0.0, 0.5]}", "{t: 0.1, offset_mm: [0, 0, 1]}",
       "tools[0].grab.path[0].offset_mm: the first keyframe needs position_mm or at_fraction"},
      {"blade_edge_mm: [0, 0, 20]", "blade_edge_mm: [0, 20]", "tools[1].cut.blade_edge_mm: expected a list of 3 numbers"},
      {"  - label: 2", "  - label: 2\n    box: {min: [0, 0, 0], max: [1, 1, 1]}", "fixed[2]: each fixed region is exactly one of"},
      {"max: [1, 1, 0.2]", "max: [1, 1, -0.2]", "fixed[0].box_fraction.max: each max must be >= its min"},
      {"gravity_mm_per_s2", "gravity", "s.yaml: gravity: unknown key (known here:"},
      {"frame_interval_s: 0.02", "frame_interval_s: 2", "output.frame_interval_s: longer than the run"},
      {"ctsurg_scenario: 1", "ctsurg_scenario: 2", "ctsurg_scenario: this ctsurg reads version 1"},
      {"  trajectory: traj.h5\n", "", "output.trajectory: missing (required)"},
      {"      start_s: 0.1\n      end_s: 0.5", "      start_s: 0.7", "tools[0] (grab).start_s: the tool starts after the run ends"},
      {"dt_s: auto", "dt_s: 2", "time.dt_s: the step is longer than the run"},
      {"name: grab test", "name: [grab", "s.yaml: line "},
  };
  for (const auto& c : cases) {
    const std::string e = error_of(replaced(kFull, c.from, c.to));
    EXPECT_NE(e.find(c.expected), std::string::npos) << "for " << c.to << "\n got: " << e;
  }
}

TEST(Scenario, UnreadableFileIsNamed) {
  try {
    (void)ctsurg::sim::read_scenario_file("/nonexistent/s.yaml");
    ADD_FAILURE();
  } catch (const ctsurg::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/s.yaml"), std::string::npos);
  }
}

TEST(Scenario, FemKindsAndTheirRules) {
  const std::string base =
      "ctsurg_scenario: 1\nmodel:\n  kind: fem\n  tetmesh: t.h5\n  solver: static\n"
      "material: {law: stvk, preset: kidney}\ntime: {duration_s: 1}\noutput: {trajectory: o.h5}\n";
  const auto s = parse_scenario(base, "f.yaml", "/b");
  EXPECT_EQ(s.model, ctsurg::sim::ModelKind::fem);
  EXPECT_EQ(s.material_law, ctsurg::sim::FemLaw::stvk);
  EXPECT_EQ(s.fem_solver, ctsurg::sim::FemSolver::static_equilibrium);
  EXPECT_TRUE(s.grid.empty());  // no grid for an FEM scene
  const auto describe = ctsurg::sim::describe_scenario(s);
  EXPECT_NE(describe.find("\"tetmesh\": \"/b/t.h5\""), std::string::npos) << describe;
  EXPECT_EQ(describe.find("\"grid\""), std::string::npos) << describe;
  // Linear tets are cut (fem/fem_cutting.h); quadratic ones are not.
  EXPECT_EQ(parse_error(base + "tools:\n  - cut: {blade_edge_mm: [0, 0, 1], path: [{t: 0, position_mm: [0, 0, 0]}]}\n"), "(accepted)");
  EXPECT_NE(parse_error(replaced(base, "solver: static\n", "solver: static\n  elements: quadratic\n") +
                        "tools:\n  - cut: {blade_edge_mm: [0, 0, 1], path: [{t: 0, position_mm: [0, 0, 0]}]}\n")
                .find("f.yaml: tools[0]: cut needs linear (4-node) tets"),
            std::string::npos);
  EXPECT_NE(parse_error(base + "tools:\n  - probe: {radius_mm: 2, path: [{t: 0, position_mm: [0, 0, 0]}]}\n").find("probe needs solver: dynamic"),
            std::string::npos);
  EXPECT_NE(parse_error(replaced(base, "  tetmesh: t.h5\n", "")).find("model.tetmesh: missing (kind: fem needs a tet mesh)"), std::string::npos);
  EXPECT_NE(parse_error(replaced(base, "kind: fem", "kind: spring_grid\n  grid: g.h5")).find("model.solver: only for kind: fem"),
            std::string::npos);
}

TEST(Scenario, InstrumentsTheirMeshesAndOrientations) {
  const std::string base =
      "ctsurg_scenario: 1\nmodel: {kind: spring_grid, grid: g.h5}\nmaterial: {preset: liver}\ntime: {duration_s: 1}\n"
      "output: {trajectory: o.h5}\n";
  const auto s = parse_scenario(base + R"(tools:
  - instrument:
      mesh: ../instruments/probe_rod.stl
      grid_spacing_mm: 0.25
      path:
        - {t: 0, position_mm: [1, 2, 3], rotation: {axis: [0, 0, 1], angle_deg: 90}}
        - {t: 0.5, offset_mm: [0, 0, -5]}
        - {t: 1, offset_mm: [0, 0, -5], quaternion: [1, 0, 0, 0]}
)",
                                "f.yaml", "/b/s");
  ASSERT_EQ(s.tools.size(), 1u);
  const auto& t = s.tools[0];
  EXPECT_STREQ(t.kind(), "instrument");
  EXPECT_EQ(t.instrument_mesh, std::filesystem::path("/b/s/../instruments/probe_rod.stl"));
  EXPECT_EQ(t.instrument_spacing_mm, 0.25);
  ASSERT_EQ(t.path.size(), 3u);
  ASSERT_TRUE(t.path[0].rotation.has_value());
  EXPECT_NEAR((*t.path[0].rotation)[0], std::sqrt(0.5), 1e-12);
  EXPECT_NEAR((*t.path[0].rotation)[3], std::sqrt(0.5), 1e-12);
  EXPECT_FALSE(t.path[1].rotation.has_value());  // holds the previous key's
  EXPECT_EQ(*t.path[2].rotation, (ctsurg::sim::Quaternion{1, 0, 0, 0}));
  // The pipeline makes the run depend on the mesh (ctsurg-sim --describe).
  EXPECT_NE(ctsurg::sim::describe_scenario(s).find("\"instruments\": [\n    \"/b/s/../instruments/probe_rod.stl\""), std::string::npos)
      << ctsurg::sim::describe_scenario(s);

  const std::string tool = "tools:\n  - instrument:\n      mesh: m.stl\n      path:\n        - {t: 0, position_mm: [0, 0, 0]";
  EXPECT_NE(parse_error(base + tool + ", quaternion: [2, 0, 0, 0]}\n").find("f.yaml: tools[0].instrument.path[0].quaternion: is not a rotation"),
            std::string::npos)
      << parse_error(base + tool + ", quaternion: [2, 0, 0, 0]}\n");
  EXPECT_NE(parse_error(base + tool + ", quaternion: [1, 0, 0]}\n").find("expected [w, x, y, z]"), std::string::npos);
  EXPECT_NE(parse_error(base + tool + ", rotation: {axis: [0, 0, 0], angle_deg: 5}}\n").find("rotation.axis: must not be zero"),
            std::string::npos);
  EXPECT_NE(parse_error(base + tool + ", rotation: {axis: [0, 0, 1], angle_deg: 5}, quaternion: [1, 0, 0, 0]}\n")
                .find("give one of quaternion, rotation"),
            std::string::npos);
  // A grab's keyframes may carry a rotation, which turns what it holds for kind: vessel only.
  EXPECT_NE(parse_error(base + "tools:\n  - grab: {radius_mm: 2, path: [{t: 0, position_mm: [0, 0, 0], quaternion: [0, 1, 0, 0]}]}\n")
                .find("tools[0].grab.path[0].quaternion: a grab turns what it holds only for kind: vessel"),
            std::string::npos);
  EXPECT_NE(parse_error(base + "tools:\n  - instrument: {path: [{t: 0, position_mm: [0, 0, 0]}]}\n").find("tools[0].instrument.mesh"),
            std::string::npos);
  const std::string fem = "ctsurg_scenario: 1\nmodel: {kind: fem, tetmesh: t.h5, solver: static}\nmaterial: {preset: kidney}\n"
                          "time: {duration_s: 1}\noutput: {trajectory: o.h5}\n";
  EXPECT_NE(parse_error(fem + tool + "}\n").find("instrument needs solver: dynamic"), std::string::npos) << parse_error(fem + tool + "}\n");
}

TEST(Scenario, ContactSectionForTheExplicitFem) {
  const std::string fem = "ctsurg_scenario: 1\nmodel: {kind: fem, tetmesh: t.h5, solver: dynamic}\nmaterial: {preset: kidney}\n"
                          "time: {duration_s: 1}\noutput: {trajectory: o.h5}\n";
  const auto s = parse_scenario(fem + "contact:\n  self: false\n  distance_mm: 0.2\n  bodies:\n    labels: true\n"
                                      "    gap_mm: 3\n    planes:\n      - {point_mm: [1, 2, 3], normal: [0, 0, 1]}\n",
                                "f.yaml", "/b");
  EXPECT_TRUE(s.contact.enabled);
  EXPECT_FALSE(s.contact.self);
  EXPECT_EQ(s.contact.distance_mm, 0.2);
  EXPECT_TRUE(s.contact.split_labels);
  EXPECT_EQ(s.contact.gap_mm, 3);
  ASSERT_EQ(s.contact.split_planes.size(), 1u);
  EXPECT_EQ(s.contact.split_planes[0].point, (std::array<double, 3>{1, 2, 3}));
  EXPECT_NE(parse_error(replaced(fem, "solver: dynamic", "solver: static") + "contact: {self: true}\n").find("contact: only for kind: fem with solver: dynamic"),
            std::string::npos);
  EXPECT_NE(parse_error(fem + "contact:\n  bodies:\n    planes: [{point_mm: [0, 0, 0], normal: [0, 0, 0]}]\n").find("normal: must not be zero"),
            std::string::npos);
  EXPECT_NE(parse_error(fem + "contact: {distance_mm: -1}\n").find("contact.distance_mm"), std::string::npos);
  EXPECT_NE(parse_error(fem + "contact: {friction: 0.3}\n").find("unknown key"), std::string::npos);
}

TEST(Scenario, SolverSectionAxesAndTheNewFemModels) {
  const std::string base =
      "ctsurg_scenario: 1\nmodel:\n  kind: fem\n  tetmesh: t.h5\n  solver: implicit\n"
      "material: {law: corotational, preset: kidney, stiffness_damping_s: 0.01}\ntime: {duration_s: 1}\noutput: {trajectory: o.h5}\n"
      "fixed:\n  - {box_fraction: {min: [0, 0, 0], max: [1, 1, 0.1]}, axes: [z, x]}\n"
      "solver: {linear: direct, tolerance_mm: 0.05, max_newton_iterations: 7, max_cg_iterations: 300}\n";
  const auto s = parse_scenario(base, "f.yaml", "/b");
  EXPECT_EQ(s.material_law, ctsurg::sim::FemLaw::corotational);
  EXPECT_EQ(s.fem_solver, ctsurg::sim::FemSolver::implicit);
  EXPECT_DOUBLE_EQ(s.stiffness_damping_s, 0.01);
  ASSERT_EQ(s.fixed.size(), 1u);
  EXPECT_EQ(s.fixed[0].axes, 5);  // x and z
  EXPECT_EQ(s.solver.linear, ctsurg::sim::FemLinearSolve::direct);
  EXPECT_DOUBLE_EQ(s.solver.tolerance_mm, 0.05);
  EXPECT_EQ(s.solver.max_newton_iterations, 7);
  EXPECT_EQ(s.solver.max_cg_iterations, 300);
  EXPECT_NE(ctsurg::sim::describe_scenario(s).find("\"solver\": \"implicit\""), std::string::npos);
  expect_error(replaced(base, "axes: [z, x]", "axes: [z, w]"), "f.yaml: fixed[0].axes[1]");
  expect_error(replaced(base, "axes: [z, x]", "axes: [z, z]"), "'z' is named twice");
  expect_error(replaced(base, "axes: [z, x]", "axes: []"), "name at least one of x, y, z");
  const std::string dynamic = replaced(replaced(base, "solver: implicit", "solver: dynamic"), ", stiffness_damping_s: 0.01", "");
  expect_error(dynamic, "fixed[0].axes: fixing some axes only needs solver: static or implicit");
  expect_error(replaced(base, "tolerance_mm: 0.05", "tolerance_mm: 20"), "solver.tolerance_mm: must be <= 10 mm");
  expect_error(replaced(base, "tolerance_mm: 0.05", "tolerance_mm: -1"), "solver.tolerance_mm");
  expect_error(replaced(base, "linear: direct", "linear: magic"), "solver.linear");
  expect_error(replaced(base, "max_newton_iterations: 7", "max_newton_iterations: 0"), "solver.max_newton_iterations");
  expect_error(replaced(base, "max_cg_iterations: 300", "restarts: 3"), "solver.restarts");
  expect_error(replaced(base, "solver: implicit", "solver: static"), "material.stiffness_damping_s: only for kind: fem with solver: implicit");
  expect_error(replaced(dynamic, ", axes: [z, x]", ""),
               "solver: only for kind: fem with solver: static or implicit");
  expect_error(replaced(base, "law: corotational", "law: hookean"),
               "f.yaml: material.law: unknown law 'hookean' (the laws: linear, stvk, neo_hookean, corotational, mooney_rivlin)");
  EXPECT_EQ(parse_scenario(replaced(base, "solver: implicit", "solver: implicit\n  elements: quadratic"), "f.yaml", "/b").fem_order, 2);
  expect_error(replaced(dynamic, "solver: dynamic", "solver: dynamic\n  elements: quadratic"), "model.elements: quadratic tets need solver: static or implicit");
  expect_error(replaced(base, "solver: implicit", "solver: implicit\n  elements: cubic"), "model.elements");
  expect_error(base + "tools:\n  - probe: {radius_mm: 2, path: [{t: 0, position_mm: [0, 0, 0]}]}\n", "probe needs solver: dynamic");
  // A spring model holds axes too (its particles' components); the solver section is FEM's only.
  const std::string springs =
      "ctsurg_scenario: 1\nmodel: {kind: spring_grid, grid: g.h5}\nmaterial: {preset: kidney}\ntime: {duration_s: 1}\n"
      "output: {trajectory: o.h5}\nfixed:\n  - {label: 1, axes: [y]}\n";
  EXPECT_EQ(parse_scenario(springs, "f.yaml", "/b").fixed[0].axes, 2);
  expect_error(springs + "solver: {tolerance_mm: 0.1}\n", "solver: only for kind: fem");
  // Issue 32: the nonlinear iteration (solver.nonlinear) and the implicit scheme (time.integrator).
  EXPECT_EQ(s.solver.nonlinear, ctsurg::sim::FemNonlinearSolve::newton);
  EXPECT_EQ(s.implicit_scheme, ctsurg::sim::FemImplicitScheme::backward_euler);
  const auto q = parse_scenario(replaced(replaced(base, "linear: direct", "nonlinear: quasi_newton"), "time: {duration_s: 1}",
                                         "time: {duration_s: 1, integrator: midpoint}"),
                                "f.yaml", "/b");
  EXPECT_EQ(q.solver.nonlinear, ctsurg::sim::FemNonlinearSolve::quasi_newton);
  EXPECT_EQ(q.implicit_scheme, ctsurg::sim::FemImplicitScheme::midpoint);
  expect_error(replaced(base, "linear: direct", "nonlinear: bfgs"), "solver.nonlinear");
  expect_error(replaced(base, "time: {duration_s: 1}", "time: {duration_s: 1, integrator: bdf2}"), "time.integrator");
  expect_error(replaced(replaced(replaced(base, "solver: implicit", "solver: static"), ", stiffness_damping_s: 0.01", ""), "time: {duration_s: 1}",
                        "time: {duration_s: 1, integrator: midpoint}"),
               "time.integrator: only for kind: fem with solver: implicit");
}

// The law is the material section's (material.law) with its own constants; the old spelling
// model.material_law is refused with the new one in the message.
TEST(Scenario, MaterialLawAndItsConstants) {
  const std::string base =
      "ctsurg_scenario: 1\nmodel:\n  kind: fem\n  tetmesh: t.h5\n  solver: static\n"
      "material: {law: mooney_rivlin, c10_pa: 3000, c01_pa: 500, preset: liver}\ntime: {duration_s: 1}\noutput: {trajectory: o.h5}\n";
  const auto s = parse_scenario(base, "f.yaml", "/b");
  EXPECT_EQ(s.material_law, ctsurg::sim::FemLaw::mooney_rivlin);
  EXPECT_DOUBLE_EQ(s.law_constants[0], 3000);
  EXPECT_DOUBLE_EQ(s.law_constants[1], 500);
  EXPECT_DOUBLE_EQ(s.material.poisson_ratio, 0.45);                        // the preset's
  EXPECT_NEAR(s.material.youngs_modulus_pa, 2 * 2 * 3500 * 1.45, 1e-9);  // from the constants, not the preset
  expect_error(replaced(base, "c01_pa: 500, ", ""), "f.yaml: material.c01_pa: missing");
  expect_error(replaced(base, "c01_pa: 500", "c01_pa: -5"), "f.yaml: material.c01_pa");
  expect_error(replaced(base, "preset: liver", "preset: liver, youngs_modulus_pa: 5000"),
               "material.youngs_modulus_pa: mooney_rivlin's stiffness comes from its constants");
  expect_error(replaced(base, "preset: liver", "preset: liver, poisson_ratio: 0.05"), "material.poisson_ratio: mooney_rivlin needs lambda - 4 c01 > 0");
  expect_error(replaced(base, "law: mooney_rivlin", "law: neo_hookean"),
               "material.c10_pa: a constant of law mooney_rivlin, and this material's law is neo_hookean");
  expect_error(replaced(base, "solver: static\n", "solver: static\n  material_law: neo_hookean\n"),
               "f.yaml: model.material_law: the law moved to the material section: write `material: {law: neo_hookean, ...}`");
  const std::string springs = "ctsurg_scenario: 1\nmodel: {kind: spring_grid, grid: g.h5}\nmaterial: {preset: kidney, law: linear}\n"
                              "time: {duration_s: 1}\noutput: {trajectory: o.h5}\n";
  expect_error(springs, "f.yaml: material.law: only for kind: fem");
  expect_error(replaced(springs, "law: linear", "c10_pa: 4"), "material.c10_pa: a constant of law mooney_rivlin, and this material's law is the spring_grid model's own");
}

// Each tet label its own material (material.labels; kind: fem): the section's law is their default,
// each label gives its preset or values; what does not fit is refused naming the field.
TEST(Scenario, MaterialPerLabel) {
  const std::string base =
      "ctsurg_scenario: 1\nmodel: {kind: fem, tetmesh: t.h5, solver: dynamic}\n"
      "material:\n  law: neo_hookean\n  damping_per_s: 10\n  labels:\n    5: {preset: liver}\n"
      "    2: {preset: kidney, law: mooney_rivlin, c10_pa: 1500, c01_pa: 200}\n"
      "time: {duration_s: 1}\noutput: {trajectory: o.h5}\n";
  const auto s = parse_scenario(base, "f.yaml", "/b");
  ASSERT_EQ(s.label_materials.size(), 2u);
  EXPECT_EQ(s.label_materials[0].label, 2);  // increasing labels
  EXPECT_EQ(s.label_materials[0].law, ctsurg::sim::FemLaw::mooney_rivlin);
  EXPECT_NEAR(s.label_materials[0].material.youngs_modulus_pa, 2 * 2 * 1700 * 1.45, 1e-9);
  EXPECT_EQ(s.label_materials[0].field, "material.labels.2");
  EXPECT_EQ(s.label_materials[1].label, 5);
  EXPECT_EQ(s.label_materials[1].law, ctsurg::sim::FemLaw::neo_hookean);
  EXPECT_EQ(s.label_materials[1].material.youngs_modulus_pa, 5.5e3);
  EXPECT_DOUBLE_EQ(s.damping_per_s, 10);
  EXPECT_EQ(ctsurg::sim::model_label(s), "fem mooney_rivlin+neo_hookean (dynamic)");
  expect_error(replaced(base, "5: {preset: liver}", "5: {preset: spleen}"), "f.yaml: material.labels.5.preset: unknown material preset 'spleen'");
  expect_error(replaced(base, "5: {preset: liver}", "liver: {preset: liver}"), "material.labels.liver: a tissue label is a whole number from 1 to 65535");
  expect_error(replaced(base, "5: {preset: liver}", "5: {poisson_ratio: 0.3}"), "material.labels.5: give a preset or youngs_modulus_pa");
  expect_error(replaced(base, "5: {preset: liver}", "5: {preset: liver, poisson_ratio: 0.6}"), "material.labels.5.poisson_ratio: must be in (-1, 0.5)");
  expect_error(replaced(base, "5: {preset: liver}", "5: {preset: liver, damping_per_s: 3}"), "material.labels.5.damping_per_s: unknown key");
  expect_error(replaced(base, "  damping_per_s: 10\n", "  preset: liver\n"), "material.preset: with material.labels each label gives its own material");
  expect_error(replaced(base, "c01_pa: 200", "c01_pa: 200, youngs_modulus_pa: 3"), "material.labels.2.youngs_modulus_pa: mooney_rivlin's stiffness comes from its constants");
  // Inclusions: spheres of another material.
  const std::string inclusion = replaced(base, "  damping_per_s: 10\n",
                                         "  damping_per_s: 10\n  inclusions:\n    - {sphere: {at_fraction: [0.5, 0.5, 0.5], radius_mm: 8}, preset: tumour}\n");
  const auto si = parse_scenario(inclusion, "f.yaml", "/b");
  ASSERT_EQ(si.inclusions.size(), 1u);
  EXPECT_EQ(si.inclusions[0].centre.kind, ctsurg::sim::PointSpec::Kind::at_fraction);
  EXPECT_EQ(si.inclusions[0].radius_mm, 8);
  EXPECT_EQ(si.inclusions[0].material.youngs_modulus_pa, 40e3);
  EXPECT_EQ(si.inclusions[0].law, ctsurg::sim::FemLaw::neo_hookean);
  EXPECT_EQ(si.inclusions[0].field, "material.inclusions[0]");
  expect_error(replaced(inclusion, "radius_mm: 8", "radius_mm: -8"), "material.inclusions[0].sphere.radius_mm");
  expect_error(replaced(inclusion, "at_fraction: [0.5, 0.5, 0.5], ", ""), "material.inclusions[0].sphere: give exactly one of position_mm, at_fraction");
  expect_error(replaced(inclusion, "{sphere: {at_fraction: [0.5, 0.5, 0.5], radius_mm: 8}, ", "{"), "material.inclusions[0].sphere: missing");
  const std::string springs = "ctsurg_scenario: 1\nmodel: {kind: spring_grid, grid: g.h5}\nmaterial: {labels: {1: {preset: kidney}}}\n"
                              "time: {duration_s: 1}\noutput: {trajectory: o.h5}\n";
  expect_error(springs, "f.yaml: material.labels: not for kind: spring_grid, whose kernel has one stiffness per spring direction; "
                       "kind: explicit_springs runs the same grid's springs");
  // The explicit springs take a material per label and inclusions; the vessel does not.
  const auto explicit_springs = parse_scenario(replaced(springs, "spring_grid", "explicit_springs"), "f.yaml", "/b");
  ASSERT_EQ(explicit_springs.label_materials.size(), 1u);
  EXPECT_EQ(explicit_springs.label_materials[0].material.name, "kidney");
  expect_error(replaced(springs, "material: {labels: {1: {preset: kidney}}}",
                        "material: {preset: liver, inclusions: [{sphere: {at_fraction: [0.5, 0.5, 0.5], radius_mm: 8}, preset: tumour}]}"),
               "f.yaml: material.inclusions: not for kind: spring_grid");
  expect_error(replaced(springs, "material: {labels: {1: {preset: kidney}}}", "material: {preset: liver, law: linear}"),
               "f.yaml: material.law: only for kind: fem");
}

TEST(Scenario, RenderRequestsAreChecked) {
  const std::string base = std::string(kFull) + "render:\n  - {name: a, layout: heat-map, frames: \"10\", size: 256}\n";
  const auto s = parse_scenario(base, "s.yaml", "/base");
  ASSERT_EQ(s.render.size(), 1u);
  EXPECT_EQ(s.render[0].layout, "heat-map");
  EXPECT_EQ(s.render[0].size, 256);
  EXPECT_NE(error_of(base + "  - {name: a}\n").find("render[1].name: 'a' is used twice"), std::string::npos);
  EXPECT_NE(error_of(base + "  - {name: a/b}\n").find("render[1].name: use letters"), std::string::npos);
  EXPECT_NE(error_of(base + "  - {name: b, layout: mosaic}\n").find("render[1].layout: 'mosaic' is not one of"), std::string::npos);
  // A viewer (animated glTF + HTML page) plays every frame unless told otherwise, and compares nothing.
  const auto v = parse_scenario(base + "  - {name: b, layout: viewer}\n  - {name: c, layout: viewer, frames: \"0:10:2\"}\n",
                                "s.yaml", "/base");
  EXPECT_EQ(v.render[1].frames, "all");
  EXPECT_EQ(v.render[2].frames, "0:10:2");
  EXPECT_NE(error_of(base + "  - {name: b, layout: viewer, reference: rest}\n").find("render[1].reference: a viewer plays one model"),
            std::string::npos);
}

// A fuzz finding (tests/fuzz_regressions/README.md): a map with a list as a key made yaml-cpp's
// conversion exception escape the parser. Now an InputError naming the file.
TEST(Scenario, YamlShapesTheChecksDidNotForeseeAreInputErrors) {
  const std::string text = ctsurg::test::read_bytes(ctsurg::test::source_dir() / "tests" / "fuzz_regressions" /
                                                    "fuzz_scenario" / "crash-c4056c39");
  ASSERT_FALSE(text.empty());
  EXPECT_THROW(parse_scenario(text, "fuzz.yaml", "/nonexistent"), ctsurg::InputError);
  for (const char* bad : {"? [a, b]\n: 1\n", "{[1]: 2}", "name: x\n? {a: 1}\n: y\n", "ctsurg_scenario: [1\n"}) {
    try {
      parse_scenario(bad, "s.yaml", "/nonexistent");
      ADD_FAILURE() << "accepted: " << bad;
    } catch (const ctsurg::InputError& e) {
      EXPECT_EQ(e.file(), "s.yaml") << e.what();
    }
  }
}

TEST(Scenario, SutureFieldsAndTheirChecks) {
  const std::string suture = R"(
  - suture:
      start_s: 0.3
      end_s: 0.5
      target_length_mm: 1.5
      stiffness_ratio: 0.5
      stitches:
        - {a: [20, -15, 40], b: [22, -15, 40]}
      along: {from: [21, -18, 40], to: [21, -12, 40], count: 3, width_mm: 4, across: [1, 0, 0]}
time:)";
  const std::string text = replaced(kFull, "\ntime:", suture);
  const auto s = parse_scenario(text, "s.yaml", "/base");
  ASSERT_EQ(s.tools.size(), 3u);
  const auto& t = s.tools[2];
  EXPECT_STREQ(t.kind(), "suture");
  EXPECT_EQ(t.label, "tools[2] (suture)");
  EXPECT_DOUBLE_EQ(t.start_s, 0.3);
  EXPECT_DOUBLE_EQ(t.end_s, 0.5);
  EXPECT_DOUBLE_EQ(t.stitch_target_mm, 1.5);
  EXPECT_DOUBLE_EQ(t.stitch_stiffness_ratio, 0.5);
  ASSERT_EQ(t.stitches.size(), 1u);
  EXPECT_EQ(t.stitches[0].field, "tools[2].suture.stitches[0]");
  EXPECT_EQ(t.stitches[0].b, (std::array<double, 3>{22, -15, 40}));
  ASSERT_TRUE(t.along.has_value());
  EXPECT_EQ(t.along->count, 3);
  EXPECT_DOUBLE_EQ(t.along->width_mm, 4);
  EXPECT_TRUE(s.close_cuts);  // on by default
  EXPECT_FALSE(parse_scenario(replaced(text, "  coupling: nearest_particle", "  coupling: nearest_particle\n  close_cuts: false"), "s.yaml",
                              "/base")
                   .close_cuts);
  struct Case {
    std::string from, to, expected;
  };
  const Case cases[] = {
      {"b: [22, -15, 40]", "b: [20, -15, 40]", "s.yaml: tools[2].suture.stitches[0].b: is the same point as a"},
      {"b: [22, -15, 40]", "b: [60, -15, 40]", "s.yaml: tools[2].suture.stitches[0].b: is 40 mm from a (at most 30 mm)"},
      {"end_s: 0.5\n      target", "end_s: 0.2\n      target", "s.yaml: tools[2].suture.end_s: must be after start_s"},
      {"      end_s: 0.5\n      target", "      target", "s.yaml: tools[2].suture.end_s: missing"},
      {"stiffness_ratio: 0.5", "stiffness_ratio: 0", "tools[2].suture.stiffness_ratio: must be > 0"},
      {"target_length_mm: 1.5", "target_length_mm: -1", "tools[2].suture.target_length_mm: must be >= 0"},
      {", across: [1, 0, 0]}", "}", "(accepted)"},  // without across: the timeline finds the outward side
      {"from: [21, -18, 40], to: [21, -12, 40]", "from: [21, -18, 40], to: [21, -18, 40]",
       "tools[2].suture.along.to: is the same point as from"},
      {"across: [1, 0, 0]", "across: [0, 1, 0]", "tools[2].suture.along.across: must not be zero or along the line"},
      {"count: 3", "count: 0", "tools[2].suture.along.count"},
      {"      stitches:\n        - {a: [20, -15, 40], b: [22, -15, 40]}\n      along: {from: [21, -18, 40], to: [21, -12, 40], count: 3, width_mm: 4, across: [1, 0, 0]}\n",
       "", "tools[2].suture: give stitches"},
      {"      start_s: 0.3\n      end_s: 0.5", "      start_s: 0.7\n      end_s: 0.9", "tools[2] (suture).start_s: the tool starts after the run ends"},
      {"kind: spring_grid", "kind: fem\n  tetmesh: t.h5",
       "tools[2]: suture runs on the spring models only (kind: spring_grid or explicit_springs); stitches for kind: fem are not implemented"},
  };
  for (const auto& c : cases) {
    const std::string e = error_of(replaced(text, c.from, c.to));
    EXPECT_NE(e.find(c.expected), std::string::npos) << "for " << c.to << "\n got: " << e;
  }
  EXPECT_NE(error_of(replaced(replaced(kFull, "kind: spring_grid", "kind: fem\n  tetmesh: t.h5\n  close_cuts: true"), "  coupling: nearest_particle\n", ""))
                .find("model.close_cuts: only for the spring models"),
            std::string::npos);
}

TEST(Scenario, CauteryFieldsAndTheModelsThatCanRemoveTissue) {
  const std::string cautery = R"(
  - cautery:
      radius_mm: 2.5
      rate_mm3_per_s: 40
      start_s: 0.2
      end_s: 0.4
      path:
        - {t: 0.2, position_mm: [20, -15, 40]}
        - {t: 0.4, offset_mm: [0, 0, 4]}
time:)";
  const std::string text = replaced(kFull, "\ntime:", cautery);
  const auto s = parse_scenario(text, "s.yaml", "/base");
  ASSERT_EQ(s.tools.size(), 3u);
  const auto& t = s.tools[2];
  EXPECT_STREQ(t.kind(), "cautery");
  EXPECT_EQ(t.acts(), ctsurg::sim::ToolPrimitive::remove);
  EXPECT_EQ(t.label, "tools[2] (cautery)");
  EXPECT_DOUBLE_EQ(t.radius_mm, 2.5);
  EXPECT_DOUBLE_EQ(t.removal_rate_mm3_s, 40);
  ASSERT_EQ(t.path.size(), 2u);
  struct Case {
    std::string from, to, expected;
  };
  const Case cases[] = {
      {"rate_mm3_per_s: 40", "rate_mm3_per_s: 0", "s.yaml: tools[2].cautery.rate_mm3_per_s: must be > 0"},
      {"rate_mm3_per_s: 40", "rate_mm3_per_s: 1e9", "tools[2].cautery.rate_mm3_per_s: must be at most"},
      {"      rate_mm3_per_s: 40\n", "", "s.yaml: tools[2].cautery.rate_mm3_per_s: missing"},
      {"rate_mm3_per_s: 40", "rate_mm3_per_s: 40\n      force_n: [0, 0, 1]", "tools[2].cautery.force_n: unknown key"},
      // The FEM removes elements under its explicit dynamics only, and not with contact.
      {"kind: spring_grid", "kind: fem\n  tetmesh: t.h5\n  solver: static",
       "tools[2]: cautery on kind: fem needs solver: dynamic and elements: linear"},
      // An unknown tool names every tool there is.
      {"  - cautery:", "  - laser:", "tools[2].laser: unknown key (known here: cautery, clamp, cut, force, grab, instrument, probe, suture)"},
  };
  for (const auto& c : cases) {
    const std::string e = error_of(replaced(text, c.from, c.to));
    EXPECT_NE(e.find(c.expected), std::string::npos) << "for " << c.to << "\n got: " << e;
  }
  // On the explicit FEM it is accepted; after a blade, or with contact, it is not.
  const std::string fem_with_blade =
      replaced(replaced(text, "kind: spring_grid", "kind: fem\n  tetmesh: t.h5\n  solver: dynamic"), "  coupling: nearest_particle\n", "");
  EXPECT_NE(error_of(fem_with_blade).find("tools[2]: cautery and a blade (tools[1] (cut)) on one kind: fem model are not supported"),
            std::string::npos)
      << error_of(fem_with_blade);
  const std::string fem = replaced(fem_with_blade,
                                   "  - cut:\n      blade_edge_mm: [0, 0, 20]\n      path:\n        - {t: 0.2, position_mm: [1, 2, 3]}\n"
                                   "        - {t: 0.3, position_mm: [11, 2, 3]}\n",
                                   "");
  EXPECT_EQ(error_of(fem), "(accepted)");
  EXPECT_NE(error_of(fem + "contact: {self: true}\n").find("contact: not with a tool that removes tissue (tools[1] (cautery))"),
            std::string::npos)
      << error_of(fem + "contact: {self: true}\n");
}

TEST(Scenario, EveryRegisteredToolHasAParserAndAName) {
  // The registry (tool_type.h) is the only list of tools: each has a unique scenario key, a parser, and
  // a record name for the spheres the trajectory draws.
  std::set<std::string> names;
  for (const ctsurg::sim::ToolType* t : ctsurg::sim::tool_types()) {
    ASSERT_NE(t, nullptr);
    EXPECT_NE(t->parse, nullptr) << t->name;
    EXPECT_TRUE(names.insert(t->name).second) << "two tools named " << t->name;
    EXPECT_EQ(ctsurg::sim::find_tool_type(t->name), t);
    if (t->record == ctsurg::sim::ToolRecord::sphere) {
      EXPECT_STRNE(t->record_name, "") << t->name;
    }
  }
  EXPECT_EQ(ctsurg::sim::find_tool_type("laser"), nullptr);
  try {
    (void)ctsurg::sim::tool_type("laser", "live session", "tool");
    ADD_FAILURE() << "an unknown tool was accepted";
  } catch (const ctsurg::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown tool 'laser' (the tools are grab, clamp, probe"), std::string::npos) << e.what();
  }
}

// A force's grip: volume spreads it over the material (fem/fem_tools.h): kind fem only, with any solver
// (no penalty: the explicit dynamics takes it too); grip_edge_mm with it only; a force has no penalty to
// set (grip_stiffness_ratio is not its key).
TEST(Scenario, AForceSpreadOverTheVolumeIsForTheFemOnly) {
  const std::string force = R"(
  - force:
      radius_mm: 6
      force_n: [0, 0, 0.2]
      grip: volume
      grip_edge_mm: 2
      start_s: 0.1
      path:
        - {t: 0.1, position_mm: [20, -15, 40]}
time:)";
  const std::string springs = replaced(kFull, "\ntime:", force);
  EXPECT_NE(error_of(springs).find("s.yaml: tools[2].force.grip: volume needs kind: fem (the spring and vessel models load particles)"),
            std::string::npos)
      << error_of(springs);
  const std::string fem =
      replaced(replaced(springs, "kind: spring_grid", "kind: fem\n  tetmesh: t.h5\n  solver: dynamic"), "  coupling: nearest_particle\n", "");
  const std::string fem_no_cut = replaced(fem, "  - cut:\n      blade_edge_mm: [0, 0, 20]\n      path:\n        - {t: 0.2, position_mm: [1, 2, 3]}\n"
                                               "        - {t: 0.3, position_mm: [11, 2, 3]}\n", "");
  const auto s = parse_scenario(fem_no_cut, "s.yaml", "/base");
  ASSERT_EQ(s.tools.size(), 2u);
  EXPECT_EQ(s.tools[1].acts(), ctsurg::sim::ToolPrimitive::load);
  EXPECT_EQ(s.tools[1].grip, ctsurg::sim::HoldGrip::volume);
  EXPECT_DOUBLE_EQ(s.tools[1].grip_edge_mm, 2);
  EXPECT_NE(error_of(replaced(fem_no_cut, "grip_edge_mm: 2", "grip_edge_mm: 7")).find("tools[1].force.grip_edge_mm: must be <= radius_mm"),
            std::string::npos);
  EXPECT_NE(error_of(replaced(fem_no_cut, "      grip: volume\n", "")).find("tools[1].force.grip_edge_mm: applies to grip: volume only"),
            std::string::npos);
  EXPECT_NE(error_of(replaced(fem_no_cut, "grip_edge_mm: 2", "grip_stiffness_ratio: 10")).find("tools[1].force.grip_stiffness_ratio: unknown key"),
            std::string::npos);
}
