// Tests for ctsurg/sim/springs/instrument_contact.h: a rigid instrument pushes a spring model's
// particles out of itself; a sphere given as a mesh acts as the sphere probe does; the tissue stays
// out of the instrument after every step while it moves and turns (penetration under 0.4 grid
// spacings, the bound the trilinear distance gives); fixed particles stay.
#include "ctsurg/sim/springs/instrument_contact.h"

#include "ctsurg/sim/base/fixed_regions.h"
#include "ctsurg/sim/springs/spring_calibration.h"
#include "ctsurg/sim/springs/spring_engine.h"
#include "instrument_test_shapes.h"
#include "sim_test_models.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ctsurg::sim {
namespace {

// A 10 x 3 x 3 bar of 2 mm cells: particle centres x = 12 .. 30, y = -18 .. -14, z = 32 .. 36 mm; fixed at x = 12.
SpringEngine bar_engine() {
  const auto occ = test::block_occupancy(10, 3, 3, 2.0);
  SpringGridModel model = build_spring_grid_model(occ, calibrated_grid_material(material_preset("liver"), occ.geometry));
  ParticleState state = model.make_state();
  fix_particles(state, particles_in_box(model.rest_positions, {{0, -100, -100}, {12.5, 100, 100}}));
  EngineOptions o;
  o.mass_damping = 30;
  o.where = "s.yaml";
  return SpringEngine(std::move(model), std::move(state), EmbeddedSurface{}, {0, 0, 0}, o);
}

ToolInput instrument_tool(const std::shared_ptr<const Instrument>& ins, const Vec3& centre, const Quaternion& q) {
  ToolInput t;
  t.acts = ToolPrimitive::push_shape;
  t.label = "tools[0] (instrument)";
  t.active = true;
  t.centre = centre;
  t.start_centre = centre;
  t.instrument = ins;
  t.orientation = q;
  return t;
}

TEST(InstrumentContact, ASphereMeshActsAsTheSphereProbe) {
  // The same 3 mm sphere pressed 1.5 mm into the bar's top until the bar settles (3,000 steps): as a
  // mesh (an icosphere within 0.014 mm of the sphere, 0.15 mm grid) and as the probe. The bar settles
  // in the same shape to within the mesh's chord and the grid's rounding (0.027 mm measured).
  const auto sphere = std::make_shared<const Instrument>(make_instrument(test::icosphere(3, 3), "sphere", 0.15));
  SpringEngine a = bar_engine(), b = bar_engine();
  const Vec3 c{24, -16, 37.5};
  ToolInput probe;
  probe.acts = ToolPrimitive::push_sphere;
  probe.label = "tools[0] (probe)";
  probe.radius_mm = 3;
  probe.active = true;
  probe.centre = c;
  const std::vector<ToolInput> as_mesh{instrument_tool(sphere, c, kIdentityRotation)}, as_probe{probe};
  for (int s = 0; s < 3000; ++s) {
    ASSERT_TRUE(a.step(as_mesh, 1).stable);
    ASSERT_TRUE(b.step(as_probe, 1).stable);
  }
  std::vector<double> pa, pb;
  a.positions(pa);
  b.positions(pb);
  double worst = 0, deepest_push = 0;
  for (size_t i = 0; i < pa.size(); ++i) worst = std::max(worst, std::abs(pa[i] - pb[i]));
  for (size_t i = 2; i < pa.size(); i += 3) deepest_push = std::max(deepest_push, 36 - pa[i]);
  EXPECT_GT(deepest_push, 1.0);  // the sphere did press the bar in
  EXPECT_LT(worst, 0.04);
}

TEST(InstrumentContact, TissueStaysOutOfAMovingTurningInstrument) {
  // A 6 x 1.5 x 20 mm blade (a box) pressed down into the bar and turned 40 degrees about its long
  // axis while it presses: after every step no free particle is deeper in it than 0.4 grid spacings.
  const double h = 0.2;
  const auto blade = std::make_shared<const Instrument>(make_instrument(test::box_mesh({-3, -0.75, 0}, {3, 0.75, 20}), "blade", h));
  SpringEngine e = bar_engine();
  const Quaternion down = axis_angle_rotation({1, 0, 0}, 180, "t", "r");  // the blade's tip (z = 0) points down
  int64_t pushed = 0;
  double deepest = 0;
  for (int s = 0; s <= 600; ++s) {
    const double f = std::min(1.0, s / 400.0);
    const Quaternion q = slerp(down, multiply(axis_angle_rotation({0, 0, 1}, 40, "t", "r"), down), f);
    const Vec3 c{22, -16, 37 - 2.5 * f};  // tip from 1 mm above the top particles to 1.5 mm into them
    const std::vector<ToolInput> tools{instrument_tool(blade, c, q)};
    ASSERT_TRUE(e.step(tools, 1).stable);
    const InstrumentView v = instrument_view(*blade, q, c);
    deepest = std::max(deepest, instrument_penetration(e.state(), v));
    for (int32_t i = 0; i < e.state().count(); ++i) {
      pushed += instrument_signed_distance(v, e.state().x[static_cast<size_t>(i)], e.state().y[static_cast<size_t>(i)],
                                           e.state().z[static_cast<size_t>(i)]) < 0.05;
    }
  }
  EXPECT_GT(pushed, 100);  // particles were in contact
  EXPECT_LT(deepest, 0.4 * h);
}

TEST(InstrumentContact, FixedParticlesStayAndOutsidePointsAreUntouched) {
  const auto occ = test::block_occupancy(3, 3, 3, 2.0);
  const SpringGridModel model = build_spring_grid_model(occ, test::test_material());
  ParticleState s = model.make_state();
  const ParticleState before = s;
  fix_particles(s, {0});
  // A box around every particle: all free ones move out, the fixed one stays.
  const Instrument big = make_instrument(test::box_mesh({-20, -30, 20}, {40, 0, 50}), "big", 0.5);
  const int64_t moved = push_out_of_instrument(s, instrument_view(big, kIdentityRotation, {0, 0, 0}));
  EXPECT_EQ(moved, s.count() - 1);
  EXPECT_EQ(s.x[0], before.x[0]);
  EXPECT_EQ(s.z[0], before.z[0]);
  // A box far away: nothing moves.
  ParticleState t = before;
  const Instrument far = make_instrument(test::box_mesh({0, 0, 0}, {5, 5, 5}), "far", 0.5);
  EXPECT_EQ(push_out_of_instrument(t, instrument_view(far, kIdentityRotation, {500, 500, 500})), 0);
  EXPECT_EQ(t.x, before.x);
}

}  // namespace
}  // namespace ctsurg::sim
