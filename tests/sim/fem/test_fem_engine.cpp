// Tests for ctsurg/sim/fem/fem_engine.h on an 8 x 2 x 2 mm bar of Kuhn tets fixed at x = 0: a
// quasi-static grab of the free end reaches its equilibrium with the grabbed nodes exactly where the
// tool put them, the embedded surface follows, and the frames come from the host whatever backend the
// solver runs on (a linear static engine on cuda solves on the CPU: it must not hand its backend to a
// host function); the dynamic engine moves the grabbed end with the tool, steps in batches and
// counts its steps; what the FEM does not take (a blade, a probe in a static run, a static run with
// nothing fixed) is refused with the file and the field.
#include "ctsurg/sim/fem/fem_engine.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/tet_mesh_file.h"
#include "ctsurg/sim/fem/fem_box_mesh.h"
#include "ctsurg/sim/surface/tet_embedding.h"
#include "fem_test_models.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ctsurg::sim {
namespace {

const std::array<int, 3> kCells{8, 2, 2};
const std::array<double, 3> kSize{8, 2, 2};

// Two triangles across the bar's top face (z = 2), embedded in its tets.
EmbeddedSurface top_surface() {
  const std::vector<float> v = {0.5f, 0.5f, 2.f, 7.5f, 0.5f, 2.f, 7.5f, 1.5f, 2.f, 0.5f, 1.5f, 2.f};
  return EmbeddedSurface(embed_surface_in_tets(v, tet_mesh_of(fem_box_mesh(kCells, kSize)), 1.0), {0, 1, 2, 0, 2, 3});
}

ToolInput grab_end(const Vec3& centre) {
  ToolInput g;
  g.acts = ToolPrimitive::hold;
  g.label = "tools[0] (grab)";
  g.radius_mm = 1.01;
  g.active = true;
  g.centre = centre;
  g.start_centre = {8, 1, 1};
  return g;
}

FemEngine static_engine(FemLaw law, Backend backend, std::vector<std::string>* notes = nullptr) {
  FemModel m = test::fem_box_model(law, kCells, kSize);
  FemEngineOptions o;
  o.solver = FemSolver::static_equilibrium;
  o.where = "s.yaml";
  if (notes) o.note = [notes](const std::string& n) { notes->push_back(n); };
  FemBoundaryConditions supports;
  supports.fixed_nodes = test::nodes_where(m, 0, 0.0);
  return FemEngine(std::move(m), std::move(supports), top_surface(), {100, 200, 300}, o, backend);
}

TEST(FemEngine, QuasiStaticGrabHoldsTheGrabbedNodesAndTheSurfaceFollows) {
  std::vector<std::string> notes;
  FemEngine e = static_engine(FemLaw::neo_hookean, Backend::cpu, &notes);
  EXPECT_TRUE(e.quasi_static());
  EXPECT_EQ(e.dt(), 0.0);
  EXPECT_EQ(e.counts().nodes, 9 * 3 * 3);
  EXPECT_EQ(e.counts().elements, 6 * 8 * 2 * 2);
  EXPECT_EQ(e.counts().fixed, 9);
  e.equilibrium({grab_end({8, 1, 2})}, 0.5);  // lift the end by 1 mm
  EXPECT_EQ(e.time(), 0.5);
  EXPECT_GT(e.steps(), 0);
  const int32_t tip = test::nodes_where(e.model(), 0, 8.0)[4];  // (8, 1, 1)
  EXPECT_NEAR(e.displacements()[3 * static_cast<size_t>(tip) + 2], 1.0, 1e-12);
  EXPECT_TRUE(e.engaged(0));
  const EngineMetrics m = e.metrics();
  EXPECT_NEAR(m.max_displacement, 1.0, 0.05);
  EXPECT_GT(m.elastic_energy, 0);
  ASSERT_EQ(m.extra.size(), e.extra_metrics().size());
  EXPECT_GT(m.extra[0], 0);  // Newton iterations of the solve
  std::vector<float> v;
  e.surface_vertices(v);
  ASSERT_EQ(v.size(), 12u);
  EXPECT_NEAR(v[2], 2.0, 0.05);  // near the fixed end: hardly moved
  EXPECT_GT(v[5], 2.5);          // near the lifted end
  ASSERT_FALSE(notes.empty());
  EXPECT_NE(notes.back().find("grabbed 6 nodes at t = 0.000000 s"), std::string::npos) << notes.back();
}

// A node held in some axes only (a roller or symmetry-plane support) is still tissue a tool can hold:
// a grab moves its free axes and a force loads them. The defect this guards against: the engine
// marked any partly held node as fixed, so on a bar fixed at x = 0 with every node held in y, a force
// at the free end was refused ("the force's sphere holds no free node") and a grab grabbed nothing.
TEST(FemEngine, ToolsActOnTheFreeAxesOfPartlyHeldNodes) {
  for (const FemLaw law : {FemLaw::linear, FemLaw::neo_hookean}) {  // the factorised linear solver and Newton
    SCOPED_TRACE(fem_law_name(law));
    const auto engine = [&] {
      FemModel m = test::fem_box_model(law, kCells, kSize);
      FemEngineOptions o;
      o.solver = FemSolver::static_equilibrium;
      o.where = "s.yaml";
      FemBoundaryConditions supports;
      supports.fixed_nodes = test::nodes_where(m, 0, 0.0);
      for (int32_t n = 0; n < m.node_count(); ++n)
        if (m.nodes[3 * static_cast<size_t>(n)] > 0) supports.fixed_components.push_back(3 * n + 1);  // y held
      return FemEngine(std::move(m), std::move(supports), top_surface(), {0, 0, 0}, o, Backend::cpu);
    };
    FemEngine grabbed = engine();
    EXPECT_EQ(grabbed.counts().fixed, 9);
    EXPECT_EQ(grabbed.counts().partly_fixed, 9 * 3 * 3 - 9);
    grabbed.equilibrium({grab_end({8, 2, 2})}, 0.5);  // up 1 mm and sideways 1 mm: only the lift is free
    const int32_t tip = test::nodes_where(grabbed.model(), 0, 8.0)[4];  // (8, 1, 1)
    EXPECT_NEAR(grabbed.displacements()[3 * static_cast<size_t>(tip) + 2], 1.0, 1e-12);
    for (int32_t n = 0; n < grabbed.model().node_count(); ++n) EXPECT_EQ(grabbed.displacements()[3 * static_cast<size_t>(n) + 1], 0.0);

    FemEngine pushed = engine();
    ToolInput f;
    f.acts = ToolPrimitive::load;
    f.label = "tools[0] (force)";
    f.radius_mm = 1.01;
    f.active = true;
    f.centre = f.start_centre = {8, 1, 1};
    f.force_n = {0, 0.01, 0.01};  // the y part meets held axes only: the supports take it
    ASSERT_NO_THROW(pushed.equilibrium({f}, 0.5));
    EXPECT_GT(pushed.displacements()[3 * static_cast<size_t>(tip) + 2], 0.01);
    for (int32_t n = 0; n < pushed.model().node_count(); ++n) EXPECT_EQ(pushed.displacements()[3 * static_cast<size_t>(n) + 1], 0.0);
  }
}

// The defect the single runner fixed: the FEM runner handed the scenario's backend to the surface's
// host-array kernel, so every FEM scenario with a surface on backend cuda threw at its first frame. A
// linear static engine solves on the CPU on every backend, so this runs without a GPU too.
TEST(FemEngine, SurfaceFramesComeFromTheHostOnEveryBackend) {
  for (const Backend backend : {Backend::cpu, Backend::cuda}) {
    SCOPED_TRACE(backend_name(backend));
    FemEngine e = static_engine(FemLaw::linear, backend);
    e.equilibrium({grab_end({8, 1, 2})}, 0.1);
    e.sync();
    std::vector<float> v;
    ASSERT_NO_THROW(e.surface_vertices(v));
    ASSERT_EQ(v.size(), 12u);
    EXPECT_GT(v[5], 2.5);
  }
}

TEST(FemEngine, DynamicGrabMovesTheEndAndIdleStepsGoInBatches) {
  FemModel m = test::fem_box_model(FemLaw::neo_hookean, kCells, kSize);
  FemEngineOptions o;
  o.solver = FemSolver::dynamic;
  o.mass_damping = 200;
  FemBoundaryConditions supports;
  supports.fixed_nodes = test::nodes_where(m, 0, 0.0);
  FemEngine e(std::move(m), std::move(supports), EmbeddedSurface(), {0, 0, 0}, o);
  EXPECT_FALSE(e.quasi_static());
  EXPECT_TRUE(e.batches_steps());
  EXPECT_GT(e.counts().critical_dt_s, e.dt());
  const double dt = e.dt();
  // The grab rises 0.5 mm over 200 steps and holds its nodes there; then nothing acts for 300 steps,
  // in one call, and the released end moves on its own.
  const int32_t tip = test::nodes_where(e.model(), 0, 8.0)[4];
  for (int k = 1; k <= 200; ++k) ASSERT_TRUE(e.step({grab_end({8, 1, 1 + 0.5 * k / 200.0})}, 1).stable);
  EXPECT_TRUE(e.engaged(0));
  e.sync();
  EXPECT_NEAR(e.displacements()[3 * static_cast<size_t>(tip) + 2], 0.5, 0.5 / 200 + 1e-6);  // within one step's travel
  ToolInput released = grab_end({8, 1, 1.5});
  released.active = false;
  ASSERT_TRUE(e.step({released}, 300).stable);
  EXPECT_EQ(e.steps(), 500);
  EXPECT_NEAR(e.time(), 500 * dt, 1e-12);
  e.sync();
  const double z = e.displacements()[3 * static_cast<size_t>(tip) + 2];
  EXPECT_GT(std::abs(z - 0.5), 1e-3);  // no longer held
  EXPECT_LT(std::abs(z), 1.0);         // and bounded
  EXPECT_FALSE(e.engaged(0));
  std::vector<float> v;
  e.surface_vertices(v);  // no surface: the nodes
  EXPECT_EQ(v.size(), e.model().nodes.size());
}

// A grab that starts between two frames captures the nodes where they are then: under gravity the
// bar's free end sags, and a grab that starts there holds it sagged (it used to capture at the
// displacement of the last frame written: the rest state here, so the end jumped back up).
TEST(FemEngine, DynamicGrabCapturesTheNodesWhereTheyAreNow) {
  const auto sagging = [] {
    FemModel m = test::fem_box_model(FemLaw::neo_hookean, kCells, kSize);
    FemEngineOptions o;
    o.solver = FemSolver::dynamic;
    o.mass_damping = 500;
    o.gravity = {0, 0, -9810};
    FemBoundaryConditions supports;
    supports.fixed_nodes = test::nodes_where(m, 0, 0.0);
    return std::make_unique<FemEngine>(std::move(m), std::move(supports), EmbeddedSurface(), Vec3{0, 0, 0}, o);
  };
  // Where the end is after 400 steps ...
  auto reference = sagging();
  ASSERT_TRUE(reference->step({}, 400).stable);
  reference->sync();
  const int32_t tip = test::nodes_where(reference->model(), 0, 8.0)[4];
  const double sag = reference->displacements()[3 * static_cast<size_t>(tip) + 2];
  ASSERT_LT(sag, -1e-3);
  // ... is where a grab that starts then holds it (no frame was taken in between).
  auto e = sagging();
  ASSERT_TRUE(e->step({}, 400).stable);
  ToolInput hold = grab_end({8, 1, 1 + sag});
  hold.radius_mm = 0.5;
  ASSERT_TRUE(e->step({hold}, 1).stable);
  ASSERT_TRUE(e->step({hold}, 1).stable);
  e->sync();
  EXPECT_NEAR(e->displacements()[3 * static_cast<size_t>(tip) + 2], sag, 1e-4);
}

TEST(FemEngine, WhatTheFemDoesNotTakeIsRefusedWithTheField) {
  FemEngine e = static_engine(FemLaw::linear, Backend::cpu);
  ToolInput blade;
  blade.acts = ToolPrimitive::separate;
  blade.label = "tools[1] (cut)";
  {
    // Quadratic tets are not cut.
    const FemBoxMesh box = fem_box_mesh(kCells, kSize);
    FemEngineOptions o;
    o.solver = FemSolver::static_equilibrium;
    o.where = "s.yaml";
    FemModel q = build_quadratic_fem_model(box.nodes, box.tets, test::fem_material(FemLaw::neo_hookean));
    FemBoundaryConditions supports;
    supports.fixed_nodes = test::nodes_where(q, 0, 0.0);
    FemEngine quadratic(std::move(q), std::move(supports), EmbeddedSurface(), {0, 0, 0}, o);
    try {
      quadratic.equilibrium({grab_end({8, 1, 1}), blade}, 0.1);
      ADD_FAILURE() << "a blade on quadratic tets was accepted";
    } catch (const InputError& err) {
      EXPECT_EQ(err.field(), "tools[1] (cut)");
    }
  }
  ToolInput probe = blade;
  probe.acts = ToolPrimitive::push_sphere;
  probe.label = "tools[1] (probe)";
  EXPECT_THROW(e.equilibrium({probe}, 0.1), InputError);
  FemEngineOptions o;
  o.solver = FemSolver::static_equilibrium;
  o.where = "s.yaml";
  try {
    FemEngine loose(test::fem_box_model(FemLaw::linear, kCells, kSize), FemBoundaryConditions{}, EmbeddedSurface(), {0, 0, 0}, o);
    ADD_FAILURE() << "a static run with nothing fixed was accepted";
  } catch (const InputError& err) {
    EXPECT_EQ(err.file(), "s.yaml");
    EXPECT_EQ(err.field(), "fixed");
  }
  EXPECT_THROW(e.step({}, 1), RuntimeError);  // a static engine has no time steps
}

}  // namespace
}  // namespace ctsurg::sim
