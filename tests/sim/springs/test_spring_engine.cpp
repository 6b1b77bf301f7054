// Tests for ctsurg/sim/springs/spring_engine.h on a 10 x 3 x 3 bar of 2 mm cells (cell centres
// x = 12 .. 30 mm) fixed at its x = 12 end: the engine steps at its automatic step, a grab captures
// once, carries its particles with the tool (engaged) and lets go for good; a blade's sweeps cut the
// springs and the carried surface; a probe pushes the bar; a force is spread over the free particles;
// a checkpoint taken and restarted with half the step gives back the state, the time and the tools'
// holds; what a spring engine does not do (a quasi-static solve) is refused.
#include "ctsurg/sim/springs/spring_engine.h"

#include "block_surface.h"
#include "ctsurg/core/error.h"
#include "ctsurg/sim/base/fixed_regions.h"
#include "ctsurg/sim/springs/spring_calibration.h"
#include "sim_test_models.h"
#include "tool_inputs.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ctsurg::sim {
namespace {

struct Bar {
  SpringGridModel model;
  SurfaceMesh mesh;
};

Bar bar() {
  const auto occ = test::block_occupancy(10, 3, 3, 2.0);
  return {build_spring_grid_model(occ, calibrated_grid_material(material_preset("liver"), occ.geometry)), test::block_surface(occ)};
}

SpringEngine engine(bool surface = true, std::vector<std::string>* notes = nullptr) {
  Bar b = bar();
  ParticleState state = b.model.make_state();
  fix_particles(state, particles_in_box(b.model.rest_positions, {{0, -100, -100}, {12.5, 100, 100}}));
  EmbeddedSurface s;
  if (surface) s = EmbeddedSurface(couple_surface(b.mesh, b.model.lattice, b.model.cells), b.mesh.triangles);
  EngineOptions o;
  o.mass_damping = 30;
  o.where = "s.yaml";
  if (notes) o.note = [notes](const std::string& n) { notes->push_back(n); };
  return SpringEngine(std::move(b.model), std::move(state), std::move(s), {0, 0, 0}, o);
}

ToolInput sphere_tool(ToolPrimitive kind, const Vec3& centre, double radius, bool active = true) {
  return test::sphere_tool_input(kind, kind == ToolPrimitive::hold ? "grab" : kind == ToolPrimitive::load ? "force" : "probe", centre,
                                 radius, active);
}

double x_of(const SpringEngine& e, int32_t p) { return e.state().x[static_cast<size_t>(p)]; }

TEST(SpringEngine, StepsAtTheAutomaticStepAndCountsTheModel) {
  SpringEngine e = engine();
  EXPECT_FALSE(e.quasi_static());
  EXPECT_EQ(e.counts().nodes, 90);
  EXPECT_EQ(e.counts().fixed, 9);
  EXPECT_GT(e.counts().springs, 0);
  EXPECT_NEAR(e.dt(), 0.5 * e.counts().critical_dt_s, 1e-15);
  EXPECT_NEAR(e.blade_sweep_mm(), 0.5, 1e-6);  // a quarter of the 2 mm face springs
  EXPECT_TRUE(e.step({}, 3).stable);
  EXPECT_EQ(e.steps(), 3);
  EXPECT_NEAR(e.time(), 3 * e.dt(), 1e-15);
  EXPECT_THROW(e.equilibrium({}, 0.1), RuntimeError);
}

TEST(SpringEngine, GrabCarriesItsParticlesAndLetsGoForGood) {
  std::vector<std::string> notes;
  SpringEngine e = engine(true, &notes);
  const auto& model = std::get<SpringGridModel>(e.model());
  const int32_t tip = model.particle_at(10, 2, 2);  // the free end's centre, x = 30 mm
  std::vector<ToolInput> tools{sphere_tool(ToolPrimitive::hold, {30, -16, 34}, 1.5)};
  ASSERT_TRUE(e.step(tools, 1).stable);
  EXPECT_TRUE(e.engaged(0));
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("tools[0] (grab): grabbed 1 particles"), std::string::npos) << notes[0];
  tools[0].centre = {33, -16, 34};
  ASSERT_TRUE(e.step(tools, 1).stable);
  EXPECT_FLOAT_EQ(static_cast<float>(x_of(e, tip)), 33.f);  // set to the tool's centre plus its offset (0)
  tools[0].active = false;
  ASSERT_TRUE(e.step(tools, 1).stable);
  EXPECT_FALSE(e.engaged(0));
  tools[0].active = true;  // a grab that let go does not capture again
  ASSERT_TRUE(e.step(tools, 1).stable);
  EXPECT_FALSE(e.engaged(0));
  EXPECT_EQ(notes.size(), 1u);
  // A grab on empty space names the tool and the place.
  SpringEngine fresh = engine();
  try {
    (void)fresh.step({sphere_tool(ToolPrimitive::hold, {100, 100, 100}, 1.0)}, 1);
    ADD_FAILURE() << "a grab on empty space was accepted";
  } catch (const InputError& err) {
    EXPECT_EQ(err.file(), "s.yaml");
    EXPECT_EQ(err.field(), "tools[0] (grab)");
    EXPECT_NE(err.problem().find("(100.000000, 100.000000, 100.000000) LPS mm"), std::string::npos) << err.problem();
  }
}

// Issue 17: a spring-model grab moved particles declared fixed (the FEM refused the same scenario).
// A grab captures free particles only, and a grab that holds none is refused.
TEST(SpringEngine, AGrabLeavesFixedParticlesWhereTheyAre) {
  std::vector<std::string> notes;
  SpringEngine e = engine(true, &notes);
  const auto& model = std::get<SpringGridModel>(e.model());
  const int32_t fixed = model.particle_at(1, 2, 2), free = model.particle_at(2, 2, 2);  // x = 12 (fixed), 14 mm
  const float fixed_z = e.state().z[static_cast<size_t>(fixed)];
  std::vector<ToolInput> tools{sphere_tool(ToolPrimitive::hold, {13, -16, 34}, 1.2)};  // holds both
  ASSERT_TRUE(e.step(tools, 1).stable);
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("grabbed 1 particles"), std::string::npos) << notes[0];
  tools[0].centre = {13, -16, 37};
  ASSERT_TRUE(e.step(tools, 1).stable);
  EXPECT_EQ(e.state().z[static_cast<size_t>(fixed)], fixed_z) << "a fixed particle was grabbed";
  EXPECT_FLOAT_EQ(e.state().z[static_cast<size_t>(free)], 37.f);
  SpringEngine fresh = engine();
  try {
    (void)fresh.step({sphere_tool(ToolPrimitive::hold, {12, -16, 34}, 1.0)}, 1);  // only the fixed particle
    ADD_FAILURE() << "a grab holding only fixed particles was accepted";
  } catch (const InputError& err) {
    EXPECT_EQ(err.field(), "tools[0] (grab)");
    EXPECT_NE(err.problem().find("no free particle"), std::string::npos) << err.problem();
  }
}

TEST(SpringEngine, BladeSweepsCutTheSpringsAndTheSurface) {
  SpringEngine e = engine();
  const size_t triangles = e.triangles().size();
  ToolInput blade;
  blade.acts = ToolPrimitive::separate;
  blade.label = "tools[0] (cut)";
  blade.blade_edge_mm = {0, 0, 40};
  blade.active = true;
  blade.sweeps = {{Vec3{21, -40, 34}, Vec3{21, 0, 34}}};  // the plane x = 21 between cell centres 20 and 22
  ASSERT_TRUE(e.step({blade}, 1).stable);
  const EngineMetrics m = e.metrics();
  // Every spring across x = 21: 9 face springs and 2 x 12 edge springs in the xy and xz planes.
  EXPECT_EQ(m.springs_cut, 9 + 24);
  EXPECT_GT(m.triangles_removed, 0);
  EXPECT_EQ(e.triangles().size(), triangles - 3 * static_cast<size_t>(m.triangles_removed));
  blade.sweeps.clear();  // no sweep this step: nothing more is cut
  ASSERT_TRUE(e.step({blade}, 1).stable);
  EXPECT_EQ(e.metrics().springs_cut, 33);
}

TEST(SpringEngine, ProbePushesAndForceSpreadsOverTheFreeParticles) {
  SpringEngine e = engine(false);
  const auto& model = std::get<SpringGridModel>(e.model());
  const int32_t top = model.particle_at(6, 2, 3);  // x = 22, y = -16, z = 36 (the top row)
  ASSERT_TRUE(e.step({sphere_tool(ToolPrimitive::push_sphere, {22, -16, 37}, 2.0)}, 1).stable);
  EXPECT_NEAR(e.state().z[static_cast<size_t>(top)], 35.0, 1e-4);  // pushed to the sphere's surface
  SpringEngine f = engine(false);
  ToolInput force = sphere_tool(ToolPrimitive::load, {30, -16, 34}, 2.1);
  force.force_n = {0, 0, 1e-3};  // 1 mN up, over the 6 free particles within 2.1 mm of the end's centre
  ASSERT_TRUE(f.step({force}, 1).stable);
  EXPECT_TRUE(f.engaged(0));
  f.sync();
  double up = 0;
  for (int32_t i = 0; i < f.state().count(); ++i) up += f.state().z[static_cast<size_t>(i)] - model.rest_positions[3 * static_cast<size_t>(i) + 2];
  // Each moved by (F / n) / m dt^2 (one step from rest: the springs have not acted yet); float
  // positions near 34 mm resolve the 2 um moves to about 1e-3 of each.
  const double m = model.mass[0], dt = f.dt();
  EXPECT_NEAR(up, 1e3 / m * dt * dt, 1e-2 * (1e3 / m * dt * dt));
}

TEST(SpringEngine, RestartGoesBackToTheCheckpointWithHalfTheStep) {
  SpringEngine e = engine();
  ASSERT_TRUE(e.can_restart());
  std::vector<ToolInput> tools{sphere_tool(ToolPrimitive::hold, {30, -16, 34}, 1.5)};
  ASSERT_TRUE(e.step(tools, 5).stable);
  e.save_checkpoint();
  const ParticleState saved = e.state();
  const double t = e.time(), dt = e.dt();
  tools[0].centre = {34, -16, 34};
  tools[0].active = false;
  ASSERT_TRUE(e.step(tools, 20).stable);
  EXPECT_FALSE(e.engaged(0));
  e.restart_halved();
  EXPECT_EQ(e.time(), t);
  EXPECT_EQ(e.steps(), 5);
  EXPECT_EQ(e.dt(), dt / 2);
  EXPECT_EQ(e.state().x, saved.x);
  EXPECT_TRUE(e.engaged(0));  // the grab held at the checkpoint is held again
  // Velocities kept: the previous positions are halfway back.
  for (size_t i = 0; i < saved.x.size(); ++i) EXPECT_EQ(e.state().px[i], saved.x[i] - (saved.x[i] - saved.px[i]) / 2);
  EXPECT_TRUE(e.check_stability().stable);
}

}  // namespace
}  // namespace ctsurg::sim
