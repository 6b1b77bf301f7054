// Tests for ctsurg/sim/scenario/scenario_run.h on a bar of tissue written as real grid and surface
// files: a grab pulls the free end by the commanded amount while the fixed end stays; a swept blade
// cuts the bar in two (the springs, the surface's triangles, and the free half falls freely); an
// over-long step is stopped by the guard with a message, or recovered by step halvings; a grab on empty
// space is refused; runs are deterministic; the explicit model of the grid's springs follows the grid
// model; frames, metrics and tools are recorded as documented.
#include "ctsurg/sim/scenario/scenario_run.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/occupancy_grid_file.h"
#include "ctsurg/core/surface_mesh_file.h"
#include "ctsurg/core/tet_mesh_file.h"
#include "ctsurg/mesh/lattice_padding.h"
#include "ctsurg/mesh/marching_cubes.h"
#include "ctsurg/sim/fem/fem_box_mesh.h"
#include "ctsurg/sim/scenario/scenario.h"
#include "ctsurg/sim/surface/hole_filling.h"
#include "ctsurg/sim/surface/surface_measures.h"
#include "fake_engine.h"
#include "scenario_test_files.h"
#include "sim_test_models.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace fs = std::filesystem;
using namespace ctsurg;
using namespace ctsurg::sim;
using ctsurg::test::TempDir;

namespace {

// A 16 x 4 x 4 bar of 2 mm cells (x from 12 to 42 mm at the cell centres) and its surface, in `dir`.
void write_bar(const fs::path& dir, double z_offset = 0) { ctsurg::sim::test::write_block_files(dir, 16, 4, 4, 2.0, z_offset); }

// The scenario text with `tools` and `time` sections inserted.
std::string bar_scenario(const std::string& tools, const std::string& time, const std::string& extra = "") {
  return "ctsurg_scenario: 1\nmodel:\n  kind: spring_grid\n  grid: grid.h5\n  surface: surface.h5\n" + extra +
         "material:\n  youngs_modulus_pa: 20000\n  damping_per_s: 30\n"
         "fixed:\n  - box_fraction: {min: [0, 0, 0], max: [0.01, 1, 1]}\n" +
         tools + time + "output:\n  trajectory: out.h5\n  frame_interval_s: 0.01\n";
}

double max_abs(const std::vector<float>& v) {
  double m = 0;
  for (const float x : v) m = std::max(m, std::abs(static_cast<double>(x)));
  return m;
}

}  // namespace

TEST(ScenarioRun, GrabPullsTheFreeEndAndTheFixedEndStays) {
  TempDir dir;
  write_bar(dir.path());
  const std::string tools =
      "tools:\n  - grab:\n      radius_mm: 2.5\n      path:\n        - {t: 0.0, position_mm: [42, -12, 38]}\n"
      "        - {t: 0.1, offset_mm: [0, -8, 0]}\n";
  const auto s = parse_scenario(bar_scenario(tools, "time:\n  duration_s: 0.2\n"), dir.path() / "s.yaml", dir.path());
  RunReport report;
  int calls = 0;
  const Trajectory t = run_scenario(s, &report, [&](double) { ++calls; });
  EXPECT_GT(calls, 0);
  ASSERT_EQ(t.frame_count(), 21);
  EXPECT_NEAR(t.time.back(), 0.2, 0.5 * t.dt_s);
  EXPECT_EQ(report.particles, 16 * 4 * 4);
  EXPECT_EQ(report.fixed, 16);  // the x = 12 mm end
  EXPECT_GT(report.steps, 0);
  EXPECT_NEAR(t.dt_s, 0.5 * report.critical_dt_s, 1e-12);
  // The surface near the grabbed end follows the tool (8 mm towards anterior); the fixed end does not move.
  const float* last = t.frame_vertices(20);
  double end_move = 0, fixed_move = 0;
  for (int64_t v = 0; v < t.vertex_count(); ++v) {
    const double dy = last[3 * v + 1] - t.rest_vertices[static_cast<size_t>(3 * v + 1)];
    if (t.rest_vertices[static_cast<size_t>(3 * v)] > 41) end_move = std::min(end_move, dy);
    if (t.rest_vertices[static_cast<size_t>(3 * v)] < 12.5) fixed_move = std::max(fixed_move, std::abs(dy));
  }
  EXPECT_NEAR(end_move, -8.0, 1.0);
  EXPECT_LT(fixed_move, 0.05);
  // Frame 0 is the rest surface; metrics and the grab sphere are recorded per frame.
  for (int64_t v = 0; v < 3 * t.vertex_count(); ++v) EXPECT_EQ(t.vertices[static_cast<size_t>(v)], t.rest_vertices[static_cast<size_t>(v)]);
  ASSERT_NE(t.metric("max_displacement"), nullptr);
  EXPECT_NEAR(t.metric("max_displacement")->values.back(), 8.0, 0.5);
  EXPECT_GT(t.metric("elastic_energy")->values.back(), 0);
  EXPECT_GT(t.metric("enclosed_volume")->values[0], 0);
  ASSERT_EQ(t.sphere_kinds, std::vector<std::string>{"grab"});
  EXPECT_EQ(t.spheres[20 * 4 + 3], 2.5);             // active at the end
  EXPECT_NEAR(t.spheres[20 * 4 + 1], -20.0, 1e-9);  // at its last keyframe, -12 - 8
  EXPECT_EQ(t.topologies.size(), 1u);
}

TEST(ScenarioRun, SweptBladeCutsTheBarAndTheSurfaceOpens) {
  TempDir dir;
  write_bar(dir.path());
  // A blade with a 20 mm edge along z, swept along y through the whole bar at x = 27 mm (between cell
  // centres 26 and 28) from t = 0 to 0.02 s; gravity then pulls the free half down.
  const std::string tools =
      "tools:\n  - cut:\n      blade_edge_mm: [0, 0, 20]\n      path:\n        - {t: 0.0, position_mm: [27, -25, 35]}\n"
      "        - {t: 0.02, position_mm: [27, -5, 35]}\n";
  // The cut's holes are left open here (close_cuts: false), so the surface loses triangles.
  const auto s = parse_scenario(bar_scenario(tools, "time:\n  duration_s: 0.1\n", "  close_cuts: false\n") +
                                    "gravity_mm_per_s2: [0, 0, -9810]\n",
                                dir.path() / "s.yaml", dir.path());
  RunReport report;
  const Trajectory t = run_scenario(s, &report);
  // Every spring crossing the plane x = 27 between the bar's two halves: 16 face + 2 * 2 * (4*3) + ...
  // counted exactly: face springs 4 x 4 = 16, edge springs in the xy and xz planes 2 * (3 * 4) * 2 = 48.
  EXPECT_EQ(report.springs_cut, 16 + 48);
  EXPECT_EQ(t.metric("springs_cut")->values.back(), 64);
  EXPECT_GT(report.surface_triangles_removed, 0);
  EXPECT_GT(t.topologies.size(), 1u);
  EXPECT_LT(t.frame_triangles(t.frame_count() - 1).size(), t.topologies[0].size());
  // The free half fell (its vertices beyond the cut moved down by several mm at 0.1 s: the cut is
  // complete by 0.02 s, 0.5 g t^2 from then is 31 mm without damping; damping slows it), the fixed
  // half hangs at its fixed end and stays near rest.
  const float* last = t.frame_vertices(t.frame_count() - 1);
  double free_drop = 0, near_fixed = 0;
  for (int64_t v = 0; v < t.vertex_count(); ++v) {
    const double x = t.rest_vertices[static_cast<size_t>(3 * v)];
    const double dz = last[3 * v + 2] - t.rest_vertices[static_cast<size_t>(3 * v + 2)];
    if (x > 40) free_drop = std::min(free_drop, dz);
    if (x < 14) near_fixed = std::max(near_fixed, std::abs(dz));
  }
  EXPECT_LT(free_drop, -5.0);
  EXPECT_LT(near_fixed, 1.0);
  ASSERT_EQ(t.blade_count(), 1);
  EXPECT_EQ(t.blades[6], 1.0);  // active in frame 0
}

TEST(ScenarioRun, UnstableStepIsStoppedWithAMessageOrRecoveredByHalving) {
  TempDir dir;
  write_bar(dir.path());
  const std::string time_text = "time:\n  duration_s: 0.05\n  dt_s: 0.003\n";
  auto s = parse_scenario(bar_scenario("", time_text) + "gravity_mm_per_s2: [0, 0, -9810]\n", dir.path() / "s.yaml", dir.path());
  RunReport report;
  {
    // Find the critical step first; the scenario's step must be above it for the test to mean anything.
    auto probe = s;
    probe.dt_s = 0;
    probe.duration_s = 0.001;
    probe.frame_interval_s = 0.001;
    (void)run_scenario(probe, &report);
    ASSERT_GT(s.dt_s, 2.5 * report.critical_dt_s);
  }
  try {
    (void)run_scenario(s);
    ADD_FAILURE() << "an unstable run completed";
  } catch (const RuntimeError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("unstable"), std::string::npos) << m;
    EXPECT_NE(m.find("max_step_halvings"), std::string::npos) << m;
  }
  s.max_step_halvings = 4;
  const Trajectory t = run_scenario(s, &report);
  EXPECT_GT(report.halvings, 0);
  EXPECT_LE(report.dt_s, s.dt_s / 2);
  EXPECT_LT(max_abs(t.vertices), 1e3);
  for (const float v : t.vertices) ASSERT_TRUE(std::isfinite(v));
  EXPECT_EQ(t.frame_count(), 6);
}

TEST(ScenarioRun, GrabOnEmptySpaceIsRefused) {
  TempDir dir;
  write_bar(dir.path());
  const std::string tools = "tools:\n  - grab:\n      radius_mm: 1\n      path:\n        - {t: 0, position_mm: [100, 100, 100]}\n";
  const auto s = parse_scenario(bar_scenario(tools, "time:\n  duration_s: 0.02\n"), dir.path() / "s.yaml", dir.path());
  try {
    (void)run_scenario(s);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("tools[0] (grab): grabs no free particle"), std::string::npos) << e.what();
  }
  // snap_to_tissue moves the same tool onto the nearest particle.
  auto snapped = s;
  snapped.tools[0].snap_to_tissue = true;
  RunReport report;
  EXPECT_NO_THROW((void)run_scenario(snapped, &report));
}

TEST(ScenarioRun, DeterministicAndTheExplicitModelFollowsTheGrid) {
  TempDir dir;
  write_bar(dir.path());
  const std::string tools =
      "tools:\n  - probe:\n      radius_mm: 3\n      path:\n        - {t: 0.0, position_mm: [36, -15, 42]}\n"
      "        - {t: 0.05, position_mm: [36, -15, 36]}\n";
  const auto s = parse_scenario(bar_scenario(tools, "time:\n  duration_s: 0.05\n"), dir.path() / "s.yaml", dir.path());
  const Trajectory a = run_scenario(s), b = run_scenario(s);
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_GT(a.metric("surface_max_displacement")->values.back(), 1.0);  // the probe pushed the top in
  auto e = s;
  e.model = ModelKind::explicit_springs;
  const Trajectory c = run_scenario(e);
  ASSERT_EQ(c.vertices.size(), a.vertices.size());
  double worst = 0;
  for (size_t i = 0; i < a.vertices.size(); ++i) worst = std::max(worst, std::abs(double(a.vertices[i]) - c.vertices[i]));
  EXPECT_LT(worst, 1e-3);
}

TEST(ScenarioRun, FarFromTheOriginTheResultIsTheSame) {
  // The same bar 600 mm higher up (a heart's z in a CT): the run is shifted to a local frame, so the
  // displacements agree with the bar near the origin to float rounding of the outputs.
  const std::string tools =
      "tools:\n  - grab:\n      radius_mm: 2.5\n      snap_to_tissue: true\n      path:\n        - {t: 0.0, at_fraction: [1, 0, 1]}\n"
      "        - {t: 0.05, offset_mm: [0, -3, 2]}\n";
  std::vector<double> disp[2];
  for (int far = 0; far < 2; ++far) {
    TempDir dir;
    write_bar(dir.path(), far ? 600.0 : 0.0);
    const auto s = parse_scenario(bar_scenario(tools, "time:\n  duration_s: 0.08\n"), dir.path() / "s.yaml", dir.path());
    const Trajectory t = run_scenario(s);
    const float* last = t.frame_vertices(t.frame_count() - 1);
    for (int64_t i = 0; i < 3 * t.vertex_count(); ++i) disp[far].push_back(double(last[i]) - t.rest_vertices[static_cast<size_t>(i)]);
    EXPECT_NEAR(t.spheres.back() > 0 ? t.spheres[t.spheres.size() - 2] : 0.0, (far ? 600.0 : 0.0) + 40.0, 3.0);
  }
  ASSERT_EQ(disp[0].size(), disp[1].size());
  double worst = 0;
  for (size_t i = 0; i < disp[0].size(); ++i) worst = std::max(worst, std::abs(disp[0][i] - disp[1][i]));
  EXPECT_LT(worst, 1e-4);  // float spacing at 640 mm is 6e-5 mm
}

namespace {

void write_bar_tets(const fs::path& dir) { ctsurg::sim::test::write_bar_tet_mesh(dir); }

std::string fem_scenario(const std::string& law, const std::string& solver, const std::string& time) {
  return "ctsurg_scenario: 1\nmodel:\n  kind: fem\n  tetmesh: tetmesh.h5\n  surface: surface.h5\n  solver: " + solver +
         "\nmaterial:\n  law: " + law + "\n  youngs_modulus_pa: 20000\n  poisson_ratio: 0.3\n  damping_per_s: 200\n"
         "fixed:\n  - box: {min: [10, -20, 30], max: [11.5, 0, 40]}\n"
         "tools:\n  - grab:\n      radius_mm: 4.5\n      path:\n        - {t: 0.0, position_mm: [43, -15, 35]}\n"
         "        - {t: 0.05, offset_mm: [0, 0, 3]}\n" + time + "output:\n  trajectory: out.h5\n  frame_interval_s: 0.05\n";
}

}  // namespace

TEST(ScenarioRun, FemStaticAndDynamicAgreeAndTheGrabIsPrescribed) {
  TempDir dir;
  write_bar(dir.path());
  write_bar_tets(dir.path());
  RunReport sr;
  const auto st = parse_scenario(fem_scenario("neo_hookean", "static", "time:\n  duration_s: 0.2\n"), dir.path() / "s.yaml", dir.path());
  const Trajectory a = run_scenario(st, &sr);
  ASSERT_EQ(a.frame_count(), 5);
  EXPECT_EQ(a.model, "fem neo_hookean (static)");
  EXPECT_GT(a.metric("newton_iterations")->values[1], 0);  // t = 0.05 s: the grab has moved its 3 mm
  EXPECT_EQ(a.metric("newton_iterations")->values.back(), 0);  // then nothing changes: the warm start is the answer
  ASSERT_EQ(sr.notes.size(), 2u);  // the surface embedding, then the grab
  EXPECT_NE(sr.notes[1].find("grabbed 6 nodes at t = 0.0"), std::string::npos) << sr.notes[1];
  EXPECT_EQ(a.metric("kinetic_energy")->values.back(), 0);
  // The grabbed end is moved by the tool's 3 mm (nodes beside it a little more, as the bar bends),
  // the fixed end stays, and the surface follows the tets.
  EXPECT_GE(a.metric("max_displacement")->values.back(), 3.0 - 1e-9);
  EXPECT_LT(a.metric("max_displacement")->values.back(), 3.2);
  const float* last = a.frame_vertices(a.frame_count() - 1);
  for (int64_t v = 0; v < a.vertex_count(); ++v) {
    if (a.rest_vertices[static_cast<size_t>(3 * v)] < 11.5) {
      EXPECT_NEAR(last[3 * v + 2], a.rest_vertices[static_cast<size_t>(3 * v + 2)], 1e-4);
    }
  }
  EXPECT_GT(a.metric("surface_max_displacement")->values.back(), 2.5);
  // A damped dynamic run holding the same grab settles to the static shape.
  const auto dy = parse_scenario(fem_scenario("neo_hookean", "dynamic", "time:\n  duration_s: 0.2\n"), dir.path() / "s.yaml", dir.path());
  RunReport dr;
  const Trajectory b = run_scenario(dy, &dr);
  EXPECT_GT(dr.steps, 100);
  const float* lb = b.frame_vertices(b.frame_count() - 1);
  double worst = 0;
  for (int64_t i = 0; i < 3 * a.vertex_count(); ++i) worst = std::max(worst, std::abs(double(last[i]) - lb[i]));
  EXPECT_LT(worst, 0.05);
}

namespace {

// What running the scenario `text` (as dir/s.yaml) is refused with, or "(accepted)".
std::string run_refusal(const std::string& text, const fs::path& dir) {
  try {
    (void)run_scenario(parse_scenario(text, dir / "s.yaml", dir));
  } catch (const InputError& e) {
    return e.what();
  }
  return "(accepted)";
}

// The bar's tet mesh (write_bar_tet_mesh) with its halves labelled: 1 where a tet's centroid has x < 27
// mm, 2 beyond.
void write_two_label_bar(const fs::path& dir) {
  TetMesh mesh = tet_mesh_of(fem_box_mesh({8, 2, 2}, {32, 8, 8}, {11, -19, 31}));
  for (size_t e = 0; e < mesh.tet_labels.size(); ++e) {
    double cx = 0;
    for (size_t k = 0; k < 4; ++k) cx += 0.25 * mesh.nodes[3 * static_cast<size_t>(mesh.tets[4 * e + k])];
    mesh.tet_labels[e] = cx < 27 ? 1 : 2;
  }
  write_tet_mesh_file(dir / "tetmesh.h5", mesh, ctsurg::test::test_provenance());
}

}  // namespace

// Two organs in contact, as data_samples/scenarios/abdomen_contact.yaml on the bar: its halves labelled 1
// and 2, separated by contact.bodies.labels, the left end fixed and the right end pushed 0.8 mm into the
// left half. Without a surface file the trajectory draws the tet mesh's boundary: each half's own 80
// triangles (the faces where they touched included). The metrics say the surfaces never pass through
// each other and each body keeps its volume, while the left half is pushed.
TEST(ScenarioRun, FemTwoBodiesByLabelPushedTogetherStayApartAndKeepTheirVolumes) {
  TempDir dir;
  write_two_label_bar(dir.path());
  const std::string text =
      "ctsurg_scenario: 1\nmodel: {kind: fem, tetmesh: tetmesh.h5, solver: dynamic}\n"
      "material: {law: neo_hookean, youngs_modulus_pa: 20000, poisson_ratio: 0.3, damping_per_s: 200}\n"
      "fixed: [{box_fraction: {min: [0, 0, 0], max: [0.05, 1, 1]}}]\n"
      "contact: {self: true, bodies: {labels: true}}\n"
      "tools:\n  - grab: {radius_mm: 1, path: [{t: 0, position_mm: [43, -15, 35]}, {t: 0.1, offset_mm: [-0.8, 0, 0]}]}\n"
      "time: {duration_s: 0.15}\noutput: {trajectory: out.h5, frame_interval_s: 0.01}\n";
  const auto s = parse_scenario(text, dir.path() / "s.yaml", dir.path());
  const Trajectory t = run_scenario(s);
  ASSERT_EQ(t.topologies.size(), 1u);
  EXPECT_EQ(t.topologies[0].size(), 3u * 160);
  const auto& penetration = t.metric("contact_penetration")->values;
  EXPECT_LT(*std::max_element(penetration.begin(), penetration.end()), 0.05);  // mm; the detection distance is 0.47 mm
  for (const char* body : {"body_volume_0", "body_volume_1"}) {
    const auto& v = t.metric(body)->values;
    EXPECT_NEAR(v.front(), 32 * 8 * 8 / 2, 1e-6) << body;
    for (const double x : v) EXPECT_NEAR(x, v.front(), 0.02 * v.front()) << body;
  }
  // The left half's nodes on the interface (x = 27) were pushed -x by the right half.
  const float* last = t.frame_vertices(t.frame_count() - 1);
  double pushed = 0;
  for (int64_t v = 0; v < t.vertex_count(); ++v)
    if (std::abs(t.rest_vertices[static_cast<size_t>(3 * v)] - 27) < 1e-4) pushed = std::min(pushed, double(last[3 * v]) - 27);
  EXPECT_LT(pushed, -0.3);
}

// Each organ its own material (material.labels): the bar's halves labelled 1 (x < 27) and 2, pulled
// at the right end with the left end held. A soft left half and a stiff right one take the stretch in
// the soft half: the interface moves further (series springs: E2 / (E1 + E2) of a uniform pull, 0.8
// here, against 0.5 for one material; the grab's few nodes make it less uniform). A label without a
// material, or a material for a label the mesh lacks, is refused naming the field; so is an inclusion
// that holds no element.
TEST(ScenarioRun, FemEachLabelItsOwnMaterial) {
  TempDir dir;
  write_two_label_bar(dir.path());
  const auto text = [](const std::string& material) {
    return "ctsurg_scenario: 1\nmodel: {kind: fem, tetmesh: tetmesh.h5, solver: static}\nmaterial: " + material + "\n"
           "fixed: [{box_fraction: {min: [0, 0, 0], max: [0.02, 1, 1]}}]\n"
           "tools:\n  - grab: {radius_mm: 4.5, path: [{t: 0, position_mm: [43, -15, 35]}, {t: 0.1, offset_mm: [2, 0, 0]}]}\n"
           "time: {duration_s: 0.1}\noutput: {trajectory: out.h5, frame_interval_s: 0.1}\n";
  };
  const auto interface_x = [&](const std::string& material) {
    const Trajectory t = run_scenario(parse_scenario(text(material), dir.path() / "s.yaml", dir.path()));
    EXPECT_EQ(t.model, "fem linear (static)");
    const float* last = t.frame_vertices(t.frame_count() - 1);
    double sum = 0;
    int count = 0;
    for (int64_t v = 0; v < t.vertex_count(); ++v)
      if (std::abs(t.rest_vertices[static_cast<size_t>(3 * v)] - 27) < 1e-4) sum += double(last[3 * v]) - 27, ++count;
    EXPECT_GT(count, 0);
    return sum / count;
  };
  const double mixed = interface_x("{law: linear, labels: {1: {youngs_modulus_pa: 10000}, 2: {youngs_modulus_pa: 40000}}}");
  const double uniform = interface_x("{law: linear, labels: {1: {youngs_modulus_pa: 10000}, 2: {youngs_modulus_pa: 10000}}}");
  const double single = interface_x("{law: linear, youngs_modulus_pa: 10000}");
  EXPECT_EQ(uniform, single);  // two labels of one material: the one-material model, bit for bit
  EXPECT_GT(uniform, 0.2);
  EXPECT_GT(mixed, 1.25 * uniform);
  EXPECT_LT(mixed, 2.0);
  // An inclusion (material.inclusions) whose sphere holds the centroids of exactly the right half's tets
  // (centre x = 35, radius 9 mm; the centroids lie within 2.7 mm of the axis) is the labels' model: the
  // same result, bit for bit.
  const double included = interface_x("{law: linear, youngs_modulus_pa: 10000, inclusions: [{sphere: {at_fraction: [0.75, 0.5, 0.5], "
                                      "radius_mm: 9}, youngs_modulus_pa: 40000}]}");
  EXPECT_EQ(included, mixed);
  // A smaller one, in the right half's middle, stiffens less.
  const double smaller = interface_x("{law: linear, youngs_modulus_pa: 10000, inclusions: [{sphere: {at_fraction: [0.75, 0.5, 0.5], "
                                     "radius_mm: 5}, youngs_modulus_pa: 40000}]}");
  EXPECT_GT(smaller, 1.02 * uniform);
  EXPECT_LT(smaller, mixed);
  const auto error_of = [&](const std::string& material) { return run_refusal(text(material), dir.path()); };
  const std::string missing = error_of("{law: linear, labels: {1: {youngs_modulus_pa: 10000}}}");
  EXPECT_NE(missing.find("s.yaml: material.labels: the tet mesh's label 2 has no material (its labels: 1, 2)"), std::string::npos) << missing;
  const std::string extra = error_of("{law: linear, labels: {1: {preset: liver}, 2: {preset: kidney}, 7: {preset: tumour}}}");
  EXPECT_NE(extra.find("s.yaml: material.labels.7: the tet mesh"), std::string::npos) << extra;
  EXPECT_NE(extra.find("has no label 7 (its labels: 1, 2)"), std::string::npos) << extra;
  const std::string outside = error_of("{law: linear, youngs_modulus_pa: 10000, inclusions: [{sphere: {position_mm: [0, 0, 0], radius_mm: 2}, "
                                       "preset: tumour}]}");
  EXPECT_NE(outside.find("s.yaml: material.inclusions[0].sphere: holds no element of the tet mesh"), std::string::npos) << outside;
}

namespace {

// The 16 x 4 x 4 block of 2 mm cells (write_block_files; cell centres x = 12 .. 42 mm) with its halves
// labelled: 1 for the cells of x < 27 mm, 2 beyond.
void write_two_label_grid(const fs::path& dir) {
  ctsurg::sim::test::write_block_files(dir, 16, 4, 4, 2.0);
  OccupancyGrid g = read_occupancy_grid_file(dir / "grid.h5");
  for (int64_t k = 0; k < g.label.geometry.dims[2]; ++k)
    for (int64_t j = 0; j < g.label.geometry.dims[1]; ++j)
      for (int64_t i = 0; i < g.label.geometry.dims[0]; ++i) {
        const size_t at = static_cast<size_t>(i + g.label.geometry.dims[0] * (j + g.label.geometry.dims[1] * k));
        if (g.label.voxels[at] != 0 && g.label.geometry.index_to_world(Eigen::Vector3d(double(i), double(j), double(k))).x() > 27) {
          g.label.voxels[at] = 2;
        }
      }
  g.label_names = {{1, "soft"}, {2, "stiff"}};
  fs::remove(dir / "grid.h5");
  write_occupancy_grid_file(dir / "grid.h5", g, ctsurg::test::test_provenance());
}

}  // namespace

// Each organ its own material on a spring model (material.labels and inclusions, kind: explicit_springs
// from a grid): the block's soft left half (label 1) and stiff right half (label 2), the left end held
// and the right end (the cells within 4.5 mm of x = 42 mm, down to x = 38) pulled 2 mm. The soft half
// takes the stretch: the last soft cells (x = 26 mm) move 14/15 of the soft half's share of the pull,
// 15 / (15 + 11 / 4) = 0.85, so 0.79, against 14 / 26 = 0.54 for one material. Two labels of one
// material are the one-material model (to rounding); an inclusion over the right half is the labels'
// model; a label without a material, one the grid lacks, and a sphere that holds no cell are refused.
TEST(ScenarioRun, SpringsEachLabelItsOwnMaterial) {
  TempDir dir;
  write_two_label_grid(dir.path());
  const auto text = [](const std::string& material) {
    return "ctsurg_scenario: 1\nmodel: {kind: explicit_springs, grid: grid.h5}\nmaterial: " + material + "\n"
           "fixed: [{box_fraction: {min: [0, 0, 0], max: [0.02, 1, 1]}}]\n"
           "tools:\n  - grab: {radius_mm: 4.5, path: [{t: 0, position_mm: [42, -15, 35]}, {t: 0.5, offset_mm: [2, 0, 0]}]}\n"
           "time: {duration_s: 2}\noutput: {trajectory: out.h5, frame_interval_s: 1}\n";
  };
  const auto interface_x = [&](const std::string& material) {
    const Trajectory t = run_scenario(parse_scenario(text(material), dir.path() / "s.yaml", dir.path()));
    const float* last = t.frame_vertices(t.frame_count() - 1);
    double sum = 0, pulled = 0;
    int count = 0, grabbed = 0;
    for (int64_t v = 0; v < t.vertex_count(); ++v) {
      const double x = t.rest_vertices[static_cast<size_t>(3 * v)];
      if (std::abs(x - 26) < 1e-3) sum += double(last[3 * v]) - x, ++count;
      if (std::abs(x - 42) < 1e-3) pulled += double(last[3 * v]) - x, ++grabbed;
    }
    EXPECT_EQ(count, 16);
    EXPECT_EQ(grabbed, 16);
    return (sum / count) / (pulled / grabbed);  // the interface's share of the end's displacement
  };
  const std::string damped = "damping_per_s: 40, ";
  const double mixed = interface_x("{" + damped + "labels: {1: {youngs_modulus_pa: 10000}, 2: {youngs_modulus_pa: 40000}}}");
  const double uniform = interface_x("{" + damped + "labels: {1: {youngs_modulus_pa: 10000}, 2: {youngs_modulus_pa: 10000}}}");
  const double single = interface_x("{" + damped + "youngs_modulus_pa: 10000}");
  EXPECT_NEAR(uniform, single, 1e-4);
  EXPECT_NEAR(uniform, 0.54, 0.08);
  EXPECT_NEAR(mixed, 0.79, 0.08);
  EXPECT_GT(mixed, 1.4 * uniform);
  const double included = interface_x("{" + damped + "youngs_modulus_pa: 10000, inclusions: [{sphere: {position_mm: [50, -15, 35], "
                                      "radius_mm: 23.5}, youngs_modulus_pa: 40000}]}");
  EXPECT_NEAR(included, mixed, 1e-4);
  std::printf("explicit springs, interface share of the pull: one material %.4f (two labels %.4f), soft | 4x stiff %.4f, inclusion %.4f\n",
              single, uniform, mixed, included);
  const auto error_of = [&](const std::string& material) { return run_refusal(text(material), dir.path()); };
  const std::string missing = error_of("{labels: {1: {youngs_modulus_pa: 10000}}}");
  EXPECT_NE(missing.find("s.yaml: material.labels: the occupancy grid's label 2 has no material (its labels: 1, 2)"), std::string::npos) << missing;
  const std::string extra = error_of("{labels: {1: {preset: liver}, 2: {preset: kidney}, 7: {preset: tumour}}}");
  EXPECT_NE(extra.find("s.yaml: material.labels.7: the occupancy grid"), std::string::npos) << extra;
  EXPECT_NE(extra.find("has no label 7 (its labels: 1, 2)"), std::string::npos) << extra;
  const std::string outside = error_of("{youngs_modulus_pa: 10000, inclusions: [{sphere: {position_mm: [0, 0, 0], radius_mm: 2}, preset: tumour}]}");
  EXPECT_NE(outside.find("s.yaml: material.inclusions[0].sphere: holds no cell of the occupancy grid"), std::string::npos) << outside;
}

namespace {

std::string with(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

double worst_difference(const Trajectory& a, const Trajectory& b) {
  const float* la = a.frame_vertices(a.frame_count() - 1);
  const float* lb = b.frame_vertices(b.frame_count() - 1);
  double worst = 0;
  for (int64_t i = 0; i < 3 * a.vertex_count(); ++i) worst = std::max(worst, std::abs(double(la[i]) - lb[i]));
  return worst;
}

}  // namespace

TEST(ScenarioRun, FemCutSeparatesTheBarKeepsItsVolumeAndTheSolversRebuild) {
  // A blade drawn across the bar's top half at x = 27 mm (a node layer of the 4 mm tets), then the
  // free end pulled down 3 mm (the top in tension): on the explicit and the implicit solver (the latter
  // refactorises on the new mesh), the nodes of the cut are split, faces are separated, the elements'
  // volume stays the bar's 2,048 mm^3 (to the bending's small change), nothing is NaN, and the cut
  // opens: the top surface either side of it moves apart, where the whole bar only stretches.
  TempDir dir;
  write_bar(dir.path());
  write_bar_tets(dir.path());
  const std::string cut = "  - cut:\n      blade_edge_mm: [0, 0, 8]\n      start_s: 0.0\n      end_s: 0.05\n      path:\n"
                          "        - {t: 0.0, position_mm: [27, -21, 39]}\n        - {t: 0.05, position_mm: [27, -9, 39]}\n";
  for (const char* solver : {"dynamic", "implicit"}) {
    SCOPED_TRACE(solver);
    const std::string whole =
        with(fem_scenario("neo_hookean", solver, "time:\n  duration_s: 0.3\n"), "offset_mm: [0, 0, 3]", "offset_mm: [0, 0, -3]");
    const std::string text = with(whole, "tools:\n", "tools:\n" + cut);
    RunReport r;
    const Trajectory a = run_scenario(parse_scenario(text, dir.path() / "s.yaml", dir.path()), &r);
    const Trajectory b = run_scenario(parse_scenario(whole, dir.path() / "s.yaml", dir.path()));
    const auto* nodes = a.metric("nodes");
    const auto* volume = a.metric("element_volume");
    ASSERT_NE(nodes, nullptr);
    ASSERT_NE(volume, nullptr);
    EXPECT_EQ(nodes->values.front(), 9 * 3 * 3);
    EXPECT_GT(nodes->values.back(), 9 * 3 * 3);  // the top half of the x = 27 layer split
    EXPECT_LT(nodes->values.back(), 9 * 3 * 3 + 9);
    EXPECT_GT(a.metric("springs_cut")->values.back(), 0);  // faces separated
    for (const double v : volume->values) EXPECT_NEAR(v, 2048, 0.01 * 2048);
    for (const float v : a.vertices) ASSERT_TRUE(std::isfinite(v));
    // The opening at the top: the mean x displacement of the top surface just right of the cut less
    // that just left of it.
    const auto opening = [](const Trajectory& t) {
      const float* last = t.frame_vertices(t.frame_count() - 1);
      double right = 0, left = 0;
      int nr = 0, nl = 0;
      for (int64_t v = 0; v < t.vertex_count(); ++v) {
        const double x = t.rest_vertices[static_cast<size_t>(3 * v)], z = t.rest_vertices[static_cast<size_t>(3 * v + 2)];
        if (z < 38.5) continue;
        const double dx = last[3 * v] - x;
        if (x > 27 && x < 30) right += dx, ++nr;
        if (x < 27 && x > 24) left += dx, ++nl;
      }
      return right / nr - left / nl;
    };
    EXPECT_GT(opening(a), opening(b) + 0.03) << opening(a) << " " << opening(b);  // measured 0.061 against -0.004
  }
}

TEST(ScenarioRun, FemImplicitSettlesToTheStaticShapeAndCorotationalStaysCloseToNeoHookean) {
  TempDir dir;
  write_bar(dir.path());
  write_bar_tets(dir.path());
  const std::string time = "time:\n  duration_s: 0.5\n";
  RunReport str;
  const Trajectory st = run_scenario(parse_scenario(fem_scenario("neo_hookean", "static", time), dir.path() / "s.yaml", dir.path()), &str);
  RunReport ir;
  const auto implicit = parse_scenario(with(fem_scenario("neo_hookean", "implicit", time), "damping_per_s: 200", "damping_per_s: 5"),
                                       dir.path() / "s.yaml", dir.path());
  const Trajectory im = run_scenario(implicit, &ir);
  EXPECT_EQ(im.model, "fem neo_hookean (implicit)");
  EXPECT_EQ(ir.steps, 30);  // frames of 1/60 s (dt_s: auto)
  EXPECT_NEAR(im.dt_s, 1.0 / 60, 1e-15);
  EXPECT_LT(worst_difference(st, im), 1e-3);
  EXPECT_GT(im.metric("newton_iterations")->values.back(), 0);
  // Corotational linear FEM: the same 3 mm grab (small strains) within a tenth of a millimetre of
  // Neo-Hookean, but not identical.
  const Trajectory co = run_scenario(parse_scenario(fem_scenario("corotational", "static", time), dir.path() / "s.yaml", dir.path()));
  EXPECT_EQ(co.model, "fem corotational (static)");
  const double d = worst_difference(st, co);
  EXPECT_GT(d, 1e-5);
  EXPECT_LT(d, 0.1);
  // Quadratic tets (elements: quadratic): the same grab, the surface following the 10-node tets; the
  // bar bends more freely than with locking linear tets, but not far off.
  RunReport qr;
  const Trajectory quad = run_scenario(
      parse_scenario(with(fem_scenario("neo_hookean", "static", time), "solver: static", "solver: static\n  elements: quadratic"),
                     dir.path() / "s.yaml", dir.path()),
      &qr);
  EXPECT_EQ(quad.model, "fem neo_hookean quadratic (static)");
  EXPECT_GT(qr.particles, 2 * str.particles);  // the edge nodes
  const double dq = worst_difference(st, quad);
  std::printf("quadratic vs linear tets, 3 mm grab: %.3f mm apart on the surface\n", dq);
  EXPECT_GT(dq, 1e-3);
  EXPECT_LT(dq, 1.0);
  EXPECT_GE(quad.metric("max_displacement")->values.back(), 3.0 - 1e-9);
  // The solver section: a 0.5 mm budget stops earlier and stays within it.
  const Trajectory loose = run_scenario(
      parse_scenario(fem_scenario("neo_hookean", "static", time) + "solver: {linear: iterative, tolerance_mm: 0.5}\n", dir.path() / "s.yaml",
                     dir.path()));
  EXPECT_LT(worst_difference(st, loose), 0.5);
}

// A grab with grip: volume (fem/fem_grip.h) holds the bar's material by a penalty: the trajectory carries
// its load on the tissue (the pull along the grab's travel), a node grab's from the static solve's
// reactions, and the two grips move the bar alike. grip: volume on a model that cannot take it is refused
// by field.
TEST(ScenarioRun, AVolumeGripLoadsTheTissueAndTheTrajectoryCarriesTheLoad) {
  TempDir dir;
  write_bar(dir.path());
  write_bar_tets(dir.path());
  const std::string time = "time:\n  duration_s: 0.1\n";
  const std::string nodes_text = fem_scenario("neo_hookean", "static", time);
  const std::string volume_text = with(nodes_text, "      radius_mm: 4.5\n", "      radius_mm: 4.5\n      grip: volume\n");
  const Trajectory nodes = run_scenario(parse_scenario(nodes_text, dir.path() / "s.yaml", dir.path()));
  const Trajectory volume = run_scenario(parse_scenario(volume_text, dir.path() / "s.yaml", dir.path()));
  for (const Trajectory* t : {&nodes, &volume}) {
    ASSERT_EQ(t->sphere_loads.size(), static_cast<size_t>(t->frame_count()) * 7);
    const double* last = &t->sphere_loads[static_cast<size_t>(t->frame_count() - 1) * 7];
    EXPECT_EQ(last[0], 1.0);     // measured
    EXPECT_GT(last[3], 0.0);     // the grab lifts along +z: the tissue is pulled up
    // (x: the held tip cannot shorten as the lifted cantilever would, so the grab also pulls it along the bar)
    EXPECT_EQ(t->sphere_loads[0], 0.0);  // the rest frame: nothing held yet
  }
  const double pull_nodes = nodes.sphere_loads[static_cast<size_t>(nodes.frame_count() - 1) * 7 + 3];
  const double pull_volume = volume.sphere_loads[static_cast<size_t>(volume.frame_count() - 1) * 7 + 3];
  std::printf("3 mm lift of the bar: pull %.4f N by the node grab, %.4f N by the volume grip; %.3f mm apart on the surface\n", pull_nodes,
              pull_volume, worst_difference(nodes, volume));
  EXPECT_GT(pull_volume, 0.3 * pull_nodes);
  EXPECT_LT(pull_volume, 3.0 * pull_nodes);
  EXPECT_LT(worst_difference(nodes, volume), 1.5);
  // On quadratic tets, with the particles: the trajectory carries the 10-node tets over them (what
  // ParaView opens as Tetrahedron_10), and the grip pulls as on linear tets, within a factor of two.
  const Trajectory quad = run_scenario(parse_scenario(
      with(with(volume_text, "solver: static", "solver: static\n  elements: quadratic"), "  frame_interval_s: 0.05\n",
           "  frame_interval_s: 0.05\n  particles: true\n"),
      dir.path() / "s.yaml", dir.path()));
  EXPECT_EQ(quad.element_nodes, 10);
  ASSERT_GT(quad.element_count(), 0);
  EXPECT_EQ(quad.elements.size(), static_cast<size_t>(quad.element_count()) * 10);
  EXPECT_EQ(*std::max_element(quad.elements.begin(), quad.elements.end()), quad.particle_count() - 1);
  const double pull_quad = quad.sphere_loads[static_cast<size_t>(quad.frame_count() - 1) * 7 + 3];
  EXPECT_GT(pull_quad, 0.5 * pull_volume);
  EXPECT_LT(pull_quad, 2.0 * pull_volume);
  // Refused: a volume grip on the explicit dynamics, and its fields on a node grab.
  const std::string dynamic_volume = with(fem_scenario("neo_hookean", "dynamic", time), "      radius_mm: 4.5\n", "      radius_mm: 4.5\n      grip: volume\n");
  EXPECT_THROW(parse_scenario(dynamic_volume, dir.path() / "s.yaml", dir.path()), InputError);
  try {
    parse_scenario(with(nodes_text, "      radius_mm: 4.5\n", "      radius_mm: 4.5\n      grip_edge_mm: 1\n"), dir.path() / "s.yaml", dir.path());
    ADD_FAILURE() << "grip_edge_mm on a node grab was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "tools[0].grab.grip_edge_mm");
  }
}

TEST(ScenarioRun, FixingSomeAxesHoldsOnlyThoseComponents) {
  TempDir dir;
  write_bar(dir.path());
  write_bar_tets(dir.path());
  // The root end held in x only (a roller): the grab lifts the whole bar, the root slides up but not along x.
  const std::string time = "time:\n  duration_s: 0.1\n";
  const std::string root = "box: {min: [10, -20, 30], max: [11.5, 0, 40]}";
  const Trajectory roller = run_scenario(parse_scenario(with(fem_scenario("linear", "static", time), root, "{" + root + ", axes: [x]}"),
                                                        dir.path() / "s.yaml", dir.path()));
  const float* last = roller.frame_vertices(roller.frame_count() - 1);
  double lift = 0;
  for (int64_t v = 0; v < roller.vertex_count(); ++v) {
    if (roller.rest_vertices[static_cast<size_t>(3 * v)] >= 11.5) continue;
    lift = std::max(lift, double(last[3 * v + 2]) - roller.rest_vertices[static_cast<size_t>(3 * v + 2)]);
  }
  std::printf("FEM root on a roller: lifted %.3f mm by the 3 mm grab\n", lift);
  EXPECT_GT(lift, 1.0);
  // The spring grid: the root held in x only slides sideways with an 8 mm pull in -y.
  const std::string tools =
      "tools:\n  - grab:\n      radius_mm: 2.5\n      path:\n        - {t: 0.0, position_mm: [42, -12, 38]}\n"
      "        - {t: 0.1, offset_mm: [0, -8, 0]}\n";
  const std::string fix = "box_fraction: {min: [0, 0, 0], max: [0.01, 1, 1]}";
  RunReport sr;
  const Trajectory springs = run_scenario(
      parse_scenario(with(bar_scenario(tools, "time:\n  duration_s: 0.2\n"), fix, "{" + fix + ", axes: [x]}"), dir.path() / "s.yaml", dir.path()),
      &sr);
  EXPECT_EQ(sr.fixed, 0);          // none held in every axis ...
  EXPECT_EQ(sr.partly_fixed, 16);  // ... the root's particles in x only
  const float* end = springs.frame_vertices(springs.frame_count() - 1);
  double slide = 0, along = 0;
  for (int64_t v = 0; v < springs.vertex_count(); ++v) {
    if (springs.rest_vertices[static_cast<size_t>(3 * v)] >= 12.5) continue;
    slide = std::min(slide, double(end[3 * v + 1]) - springs.rest_vertices[static_cast<size_t>(3 * v + 1)]);
    along = std::max(along, std::abs(double(end[3 * v]) - springs.rest_vertices[static_cast<size_t>(3 * v)]));
  }
  std::printf("spring root on a roller: slid %.3f mm sideways, %.4f mm along x\n", slide, along);
  EXPECT_LT(slide, -1.0);  // fully fixed it stays within 0.05 mm (GrabPullsTheFreeEndAndTheFixedEndStays)
  EXPECT_LT(along, 0.05);  // the surface near the held particles follows them: no slide along x
}

// The loop itself, over an engine without physics (support/fake_engine.h).
namespace {

Scenario loop_scenario(const std::string& tools, const std::string& time) {
  return parse_scenario("ctsurg_scenario: 1\nmodel: {kind: spring_grid, grid: unread.h5}\nmaterial: {preset: liver}\n" + tools +
                            time + "output: {trajectory: out.h5, frame_interval_s: 0.05}\n",
                        "loop.yaml", ".");
}

}  // namespace

TEST(ScenarioRunLoop, RestartsFromTheLastFrameWithHalfTheStepUntilTheEngineIsStable) {
  Scenario s = loop_scenario("", "time: {duration_s: 0.2, max_step_halvings: 3}\n");
  auto fake = std::make_unique<ctsurg::sim::test::FakeEngine>(0.01);
  fake->unstable_above_dt = 0.003;
  fake->unstable_after_s = 0.09;  // frames 0 and 0.05 pass; the check at 0.1 fails until dt <= 0.003
  RunReport report;
  const Trajectory t = run_scenario(s, ScenarioEngine{std::move(fake), {}}, &report);
  EXPECT_EQ(report.halvings, 2);
  EXPECT_EQ(report.dt_s, 0.0025);
  EXPECT_EQ(t.dt_s, 0.0025);
  ASSERT_EQ(t.frame_count(), 5);
  for (int64_t f = 0; f < 5; ++f) EXPECT_NEAR(t.time[static_cast<size_t>(f)], 0.05 * f, 1e-9);
  // Restarted from the frame at 0.05 s each time (the engine's time is back there, the frames after
  // it dropped), and the trajectory's dt column shows the step each frame was made with.
  EXPECT_EQ(t.metric("dt")->values, (std::vector<double>{0.01, 0.01, 0.0025, 0.0025, 0.0025}));
  ASSERT_EQ(report.notes.size(), 2u);
  EXPECT_NE(report.notes[0].find("restarted from t = 0.050000 s with dt = 0.005000 s (fake: dt 0.010000 too large)"),
            std::string::npos) << report.notes[0];

  s.max_step_halvings = 1;
  auto again = std::make_unique<ctsurg::sim::test::FakeEngine>(0.01);
  again->unstable_above_dt = 0.003;
  again->unstable_after_s = 0.09;
  try {
    (void)run_scenario(s, ScenarioEngine{std::move(again), {}});
    ADD_FAILURE() << "a run unstable beyond its halvings completed";
  } catch (const RuntimeError& e) {
    EXPECT_NE(std::string(e.what()).find("loop.yaml: the run became unstable: fake: dt 0.005000 too large (after 1 step halvings)"),
              std::string::npos) << e.what();
  }
}

TEST(ScenarioRunLoop, AQuasiStaticEngineSolvesOncePerFrameAtTheFrameTimes) {
  const Scenario s = loop_scenario(
      "tools:\n  - grab: {radius_mm: 2, path: [{t: 0, position_mm: [100, 200, 300]}, {t: 0.2, position_mm: [100, 200, 304]}]}\n",
      "time: {duration_s: 0.2}\n");
  auto fake = std::make_unique<ctsurg::sim::test::FakeEngine>(0.0, true);
  const auto calls = fake->calls;
  RunReport report;
  const Trajectory t = run_scenario(s, ScenarioEngine{std::move(fake), {}}, &report);
  ASSERT_EQ(calls->size(), 4u);
  for (size_t k = 0; k < 4; ++k) {
    EXPECT_EQ((*calls)[k].what, "equilibrium");
    EXPECT_NEAR((*calls)[k].time, 0.05 * static_cast<double>(k + 1), 1e-12);
    ASSERT_EQ((*calls)[k].tools.size(), 1u);
    EXPECT_NEAR((*calls)[k].tools[0].centre[2], (*calls)[k].time * 20, 1e-9);  // the tool at the frame's time (local frame)
  }
  EXPECT_EQ(t.frame_count(), 5);
  EXPECT_EQ(report.steps, 4);
}

TEST(ScenarioRunLoop, StepsGoInBatchesOnlyWhileNoToolActs) {
  const Scenario s = loop_scenario(
      "tools:\n  - probe: {radius_mm: 2, start_s: 0.1, end_s: 0.15, path: [{t: 0, position_mm: [100, 200, 300]}]}\n",
      "time: {duration_s: 0.25}\n");
  auto fake = std::make_unique<ctsurg::sim::test::FakeEngine>(0.01);
  fake->batches = true;
  const auto calls = fake->calls;
  const Trajectory t = run_scenario(s, ScenarioEngine{std::move(fake), {}});
  EXPECT_EQ(t.frame_count(), 6);
  // Up to 0.05 s and on to 0.1 s: idle, one call each; then single steps while the probe's window is
  // open or ahead within the frame; after 0.15 s batches again.
  std::vector<int> batch;
  for (const auto& c : *calls) batch.push_back(c.steps);
  EXPECT_EQ(batch.front(), 5);
  EXPECT_EQ(batch.back(), 5);
  int singles = 0;
  for (const auto& c : *calls) {
    if (c.steps == 1) {
      ++singles;
      EXPECT_GT(c.time, 0.05);
      EXPECT_LT(c.time, 0.16);
    }
  }
  EXPECT_GE(singles, 5);
}

// Without a surface the particles are the trajectory's point set, and its surface displacement is
// theirs (it was once measured against the rest points in LPS, not in the run's frame: |origin|).
TEST(ScenarioRun, WithoutASurfaceTheParticlesAreThePointSet) {
  TempDir dir;
  write_bar(dir.path(), 600);
  const std::string tools =
      "tools:\n  - grab:\n      radius_mm: 2.5\n      snap_to_tissue: true\n      path:\n        - {t: 0.0, at_fraction: [1, 0, 1]}\n"
      "        - {t: 0.05, offset_mm: [0, -3, 2]}\n";
  std::string text = bar_scenario(tools, "time:\n  duration_s: 0.05\n");
  text.replace(text.find("  surface: surface.h5\n"), 22, "");
  const auto s = parse_scenario(text, dir.path() / "s.yaml", dir.path());
  ASSERT_TRUE(s.surface.empty());
  RunReport report;
  const Trajectory t = run_scenario(s, &report);
  EXPECT_EQ(t.vertex_count(), report.particles);
  EXPECT_TRUE(t.topologies[0].empty());
  const auto& surface = t.metric("surface_max_displacement")->values;
  EXPECT_EQ(surface, t.metric("max_displacement")->values);
  EXPECT_EQ(surface.front(), 0.0);
  EXPECT_NEAR(surface.back(), std::sqrt(13.0), 0.3);  // the grabbed end moved (0, -3, 2) mm
}

// The bar cut through at x = 27 mm, its free half pulled 3 mm away by a grab and let go, then sutured by
// two stitches across the top (`along`, the across direction found from the tissue) and one across the
// bottom (so the severed half cannot turn about the top stitches): the trajectory
// holds the stitches (not placed, then placed), the gap between the halves closes from 5 mm to its rest
// value 2 mm, and the cut surface stays closed (close_cuts by default) with the bar's volume less the
// cut band's. A stitch off the tissue is refused naming the file and the field.
TEST(ScenarioRun, CutThenSutureClosesTheBarAndTheSurfaceStaysClosed) {
  TempDir dir;
  write_bar(dir.path());
  const std::string tools =
      "tools:\n  - cut:\n      blade_edge_mm: [0, 0, 20]\n      path:\n        - {t: 0.0, position_mm: [27, -25, 35]}\n"
      "        - {t: 0.02, position_mm: [27, -5, 35]}\n"
      "  - grab:\n      radius_mm: 2.5\n      start_s: 0.03\n      end_s: 0.1\n      path:\n"
      "        - {t: 0.03, position_mm: [42, -15, 35]}\n        - {t: 0.08, offset_mm: [3, 0, 0]}\n"
      "  - suture:\n      start_s: 0.1\n      end_s: 0.2\n      target_length_mm: 2\n"
      "      along: {from: [27, -17, 39], to: [27, -13, 39], count: 2, width_mm: 2}\n"
      "      stitches:\n        - {a: [26, -15.2, 31], b: [28, -15.2, 31]}\n";
  const std::string text = bar_scenario(tools, "time:\n  duration_s: 0.3\n") + "  particles: true\n";
  const auto s = parse_scenario(text, dir.path() / "s.yaml", dir.path());
  RunReport report;
  const Trajectory run = run_scenario(s, &report);
  write_trajectory_file(dir.path() / "out.h5", run, ctsurg::test::test_provenance());
  const Trajectory t = read_trajectory_file(dir.path() / "out.h5");
  ASSERT_EQ(t.stitch_count(), 3);
  ASSERT_EQ(t.frame_count(), 31);
  const auto stitch = [&](int64_t f, int64_t k) { return &t.stitches[static_cast<size_t>(7 * (f * 3 + k))]; };
  EXPECT_EQ(stitch(9, 0)[6], 0.0);   // t = 0.09 s: not placed
  EXPECT_EQ(stitch(11, 1)[6], 1.0);  // t = 0.11 s: placed
  // Not placed, a stitch is drawn where the scenario puts it: the listed ones first, then the line's,
  // width_mm across the line (along +x, found from the tissue).
  EXPECT_NEAR(stitch(0, 0)[2], 31, 1e-9);
  EXPECT_NEAR(stitch(0, 1)[0], 26, 1e-6);
  EXPECT_NEAR(stitch(0, 1)[3], 28, 1e-6);
  EXPECT_NEAR(stitch(0, 1)[1], -16, 1e-6);
  // The gap across x = 27 between the halves' particles.
  const auto gap = [&](int64_t f) {
    double lo = 1e30, hi = -1e30;
    for (int64_t i = 0; i < t.particle_count(); ++i) {
      const double x = t.particles[static_cast<size_t>(3 * (f * t.particle_count() + i))];
      if (t.rest_particles[static_cast<size_t>(3 * i)] > 27) {
        lo = std::min(lo, x);
      } else {
        hi = std::max(hi, x);
      }
    }
    return lo - hi;
  };
  EXPECT_NEAR(gap(0), 2.0, 1e-4);
  EXPECT_GT(gap(10), 4.5);  // pulled open by the grab, let go at 0.1 s
  EXPECT_NEAR(gap(30), 2.0, 0.2) << "gap at 0.1 s " << gap(10) << " mm";
  // The closed surface: no boundary edge (welded at seams: none here), and the volume of the bar less the
  // cut band (one cell, 2 of its 32 mm), to 3 %.
  const std::vector<uint32_t>& last = t.frame_triangles(t.frame_count() - 1);
  EXPECT_TRUE(boundary_edges(last).empty());
  EXPECT_GT(last.size(), 0u);
  // The trajectory says which triangles close the holes (the last ones of each topology after the cut).
  ASSERT_EQ(t.closing_triangles.size(), t.topologies.size());
  EXPECT_EQ(t.closing_triangles.front(), 0);
  EXPECT_GT(t.closing_triangles.back(), 0);
  const double v0 = t.metric("enclosed_volume")->values.front(), v = t.metric("enclosed_volume")->values.back();
  EXPECT_NEAR(v, v0 * 30.0 / 32.0, 0.03 * v0) << "v0 " << v0 << " v " << v;
  // A line rising off the bar: its second stitch is 8.5 mm above the top particles (at most 3 cells, 6 mm).
  std::string off = text;
  const std::string line_end = "to: [27, -13, 39]";
  off.replace(off.find(line_end), line_end.size(), "to: [27, -13, 49]");
  const auto bad = parse_scenario(off, dir.path() / "s.yaml", dir.path());
  try {
    (void)run_scenario(bad, nullptr);
    ADD_FAILURE() << "a stitch off the tissue was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), (dir.path() / "s.yaml").string());
    EXPECT_NE(e.field().find("tools[2].suture.along (stitch 2 of 2).a"), std::string::npos) << e.what();
  }
}
