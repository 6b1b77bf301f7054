// The vessel engine (vessel_engine.h): a grab pulls and twists a vessel clamped at one end, a blade
// cuts it in two with capped ends, a force bends it; refusals (a grab that captures nothing, cuda,
// instruments).
#include "ctsurg/core/error.h"
#include "ctsurg/sim/vessel/vessel_engine.h"
#include "vessel_test_centerlines.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace {

using namespace ctsurg::sim;
using ctsurg::sim::test::straight_centerline;

// A 30 mm vessel along x (atoms at x = 0..30, radius 1.5 mm, wall 0.3 mm, E 1 MPa), its first two
// atoms fixed (a clamp).
std::unique_ptr<VesselEngine> vessel(VesselEngineOptions o = {}) {
  VesselWall w;
  w.youngs_modulus_pa = 1e6;
  w.thickness_mm = 0.3;
  VesselChain chain = build_vessel_chain(straight_centerline(31, 1.0, 1.5), {0, 0, 0}, w, "t");
  const std::vector<int32_t> fixed{chain.branch_atoms[0], chain.branch_atoms[1]};
  o.mass_damping = o.mass_damping > 0 ? o.mass_damping : 10;
  return std::make_unique<VesselEngine>(std::move(chain), fixed, Vec3{0, 0, 0}, o);
}

ToolInput vessel_grab_at(const Vec3& centre, double radius) {
  ToolInput t;
  t.acts = ToolPrimitive::hold;
  t.label = "tools[0] (grab)";
  t.radius_mm = radius;
  t.active = true;
  t.centre = centre;
  return t;
}

TEST(VesselEngine, GrabPullsBendsAndTwistsTheVessel) {
  auto e = vessel();
  EXPECT_EQ(e->counts().nodes, 31);
  EXPECT_EQ(e->counts().fixed, 2);
  std::vector<ToolInput> tools{vessel_grab_at({30, 0, 0}, 1.2)};  // the tip atom (and only it)
  const int32_t tip = e->chain().branch_atoms.back();
  for (int i = 0; i <= 30; ++i) {
    tools[0].centre = {30, 0, 10.0 * std::min(i, 15) / 15};  // lift 10 mm over 0.25 s, hold
    ASSERT_TRUE(e->step(tools, 1).stable);
  }
  EXPECT_TRUE(e->engaged(0));
  EXPECT_NEAR(e->dynamics().x[3 * static_cast<size_t>(tip) + 2], 10.0, 1e-9);
  // The middle of the vessel follows between the clamp and the grab (a bent beam, not a kink).
  const int32_t mid = e->chain().branch_atoms[15];
  const double zmid = e->dynamics().x[3 * static_cast<size_t>(mid) + 2];
  EXPECT_GT(zmid, 1.0);
  EXPECT_LT(zmid, 6.0);
  EXPECT_TRUE(e->check_stability().stable);
  const EngineMetrics m = e->metrics();
  EXPECT_GT(m.elastic_energy, 0);
  EXPECT_NEAR(m.max_displacement, 10.0, 1e-6);
  ASSERT_EQ(m.extra.size(), e->extra_metrics().size());
  EXPECT_GT(m.extra[0], 30.0);  // the chain is longer than at rest

  // A twist: a grab over the last 5 atoms turning 90 degrees about the vessel's axis.
  auto t = vessel();
  std::vector<ToolInput> twist{vessel_grab_at({28, 0, 0}, 2.2)};
  for (int i = 0; i <= 20; ++i) {
    const double a = 0.5 * std::numbers::pi * std::min(i, 10) / 10;
    twist[0].orientation = {std::cos(a / 2), std::sin(a / 2), 0, 0};
    t->step(twist, 1);
  }
  std::vector<float> v;
  t->surface_vertices(v);
  // The tip ring's first spoke turned by 90 degrees about x with the grab: from the rest surface's.
  const auto& rest = t->surface_rest_vertices();
  const size_t ring = 3 * (30 * 16);  // the last ring's first vertex
  const double ry = rest[ring + 1], rz = rest[ring + 2], y = v[ring + 1], z = v[ring + 2];
  const double turned = std::atan2(ry * z - rz * y, ry * y + rz * z) * 180 / std::numbers::pi;
  EXPECT_NEAR(turned, 90.0, 1.0);
  // The twist falls off along the vessel to the clamp: the middle ring turned part of the way.
  const size_t mid_ring = 3 * (15 * 16);
  const double my = v[mid_ring + 1], mz = v[mid_ring + 2], mry = rest[mid_ring + 1], mrz = rest[mid_ring + 2];
  const double mid_turn = std::atan2(mry * mz - mrz * my, mry * my + mrz * mz) * 180 / std::numbers::pi;
  EXPECT_GT(mid_turn, 20.0);
  EXPECT_LT(mid_turn, 70.0);
}

TEST(VesselEngine, ABladeCutsTheChainInTwoAndCapsTheEnds) {
  VesselEngineOptions o;
  o.gravity = {0, 0, -9810};
  auto e = vessel(o);
  const size_t before = e->triangles().size();
  ToolInput blade;
  blade.acts = ToolPrimitive::separate;
  blade.label = "tools[0] (cut)";
  blade.active = true;
  blade.blade_edge_mm = {0, 0, 8};
  blade.sweeps = {{Vec3{15.5, -5, 0}, Vec3{15.5, 5, 0}}};  // across the segment between x = 15 and 16
  std::vector<ToolInput> tools{blade};
  e->step(tools, 1);
  tools[0].sweeps.clear();
  EXPECT_EQ(e->metrics().springs_cut, 1);
  // The quads of one segment go (2 x 16), two caps of 14 come.
  EXPECT_EQ(e->triangles().size(), before + 3 * (2 * 14 - 2 * 16));
  // The free piece falls; the clamped piece hangs.
  for (int i = 0; i < 30; ++i) e->step(tools, 1);
  const int32_t tip = e->chain().branch_atoms.back();
  EXPECT_LT(e->dynamics().x[3 * static_cast<size_t>(tip) + 2], -10.0);
  const int32_t near_clamp = e->chain().branch_atoms[5];
  EXPECT_GT(e->dynamics().x[3 * static_cast<size_t>(near_clamp) + 2], -10.0);
  EXPECT_TRUE(e->check_stability().stable);
}

TEST(VesselEngine, ForceBendsAndRefusals) {
  auto e = vessel();
  ToolInput f;
  f.acts = ToolPrimitive::load;
  f.label = "tools[0] (force)";
  f.radius_mm = 0.5;
  f.active = true;
  f.centre = {30, 0, 0};
  f.force_n = {0, 1e-5, 0};  // 10 uN on the tip: 0.025 mm static deflection
  std::vector<ToolInput> tools{f};
  for (int i = 0; i < 60; ++i) e->step(tools, 1);
  EXPECT_GT(e->dynamics().x[3 * static_cast<size_t>(e->chain().branch_atoms.back()) + 1], 0.01);

  auto g = vessel();
  std::vector<ToolInput> miss{vessel_grab_at({15, 10, 0}, 2)};  // 10 mm off the centerline
  try {
    g->step(miss, 1);
    FAIL() << "a grab that captures nothing must be refused";
  } catch (const ctsurg::InputError& err) {
    EXPECT_NE(std::string(err.what()).find("tools[0] (grab)"), std::string::npos) << err.what();
    EXPECT_NE(std::string(err.what()).find("captures no atom"), std::string::npos) << err.what();
  }
  ToolInput ins;
  ins.acts = ToolPrimitive::push_shape;
  ins.label = "tools[1] (instrument)";
  EXPECT_THROW(vessel()->step({ins}, 1), ctsurg::InputError);
  VesselWall w;
  w.youngs_modulus_pa = 1e6;
  w.thickness_mm = 0.3;
  EXPECT_THROW(VesselEngine(build_vessel_chain(straight_centerline(5, 1.0, 1.0), {0, 0, 0}, w, "t"), {}, Vec3{0, 0, 0}, {}, Backend::cuda),
               ctsurg::InputError);
}

}  // namespace
