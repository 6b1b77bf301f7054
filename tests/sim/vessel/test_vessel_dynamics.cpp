// The wall's calibration (vessel_calibration.h), the chain (vessel_chain.h) and its dynamics
// (vessel_dynamics.h): a clamped cantilever against beam theory in bending, stretch and twist; a Y's
// shared junction atom; damped dynamics settling to the static answer at a frame-rate step; stability
// under gravity for thousands of atoms.
#include "ctsurg/core/error.h"
#include "ctsurg/sim/vessel/vessel_calibration.h"
#include "ctsurg/sim/vessel/vessel_chain.h"
#include "ctsurg/sim/vessel/vessel_dynamics.h"
#include "vessel_test_centerlines.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace {

using namespace ctsurg::sim;
using ctsurg::sim::test::straight_centerline;
using ctsurg::sim::test::y_centerline;

constexpr double kPi = std::numbers::pi;

VesselWall artery_wall() {
  VesselWall w;
  w.youngs_modulus_pa = 1e6;  // 1 MPa
  w.poisson_ratio = 0.45;
  w.thickness_mm = 0.2;
  w.density = 1.06e-3;
  return w;
}

TEST(VesselCalibration, TubeSectionAndStiffnesses) {
  const TubeSection s = tube_section(2.0, 0.4);
  EXPECT_NEAR(s.area, 2 * kPi * 2.0 * 0.4, 1e-12);  // pi((r+t/2)^2 - (r-t/2)^2) = 2 pi r t
  EXPECT_NEAR(s.second_moment, kPi / 4 * (std::pow(2.2, 4) - std::pow(1.8, 4)), 1e-12);
  EXPECT_NEAR(s.polar_moment, 2 * s.second_moment, 1e-12);
  EXPECT_NEAR(s.lumen_area, kPi * 1.8 * 1.8, 1e-12);
  const TubeSection solid = tube_section(0.5, 2.0);  // t/2 >= r: a solid rod of radius 1.5
  EXPECT_NEAR(solid.area, kPi * 1.5 * 1.5, 1e-12);
  EXPECT_EQ(solid.lumen_area, 0);

  VesselWall w = artery_wall();
  const ChainStiffness k = tube_stiffness(w, 2.0);
  const TubeSection t = tube_section(2.0, 0.2);
  EXPECT_NEAR(k.stretch, 1e6 * t.area, 1e-6);
  EXPECT_NEAR(k.bending, 1e6 * t.second_moment, 1e-6);
  EXPECT_NEAR(k.torsion, 1e6 / (2 * 1.45) * t.polar_moment, 1e-6);
  EXPECT_NEAR(k.shear, 2 * 1.45 / (4 + 3 * 0.45) * 1e6 / 2.9 * t.area, 1e-6);
  EXPECT_NEAR(k.mass_per_mm, 1.06e-3 * (t.area + t.lumen_area), 1e-15);
  w.blood_filled = false;
  EXPECT_NEAR(tube_stiffness(w, 2.0).mass_per_mm, 1.06e-3 * t.area, 1e-15);
  w.thickness_mm = 0;
  EXPECT_THROW(validate_vessel_wall(w, "s.yaml"), ctsurg::InputError);
}

TEST(VesselChain, AtomsSegmentsJointsAndJunctions) {
  const VesselChain straight = build_vessel_chain(straight_centerline(11, 1.0, 2.0), {0, 0, 0}, artery_wall(), "t");
  EXPECT_EQ(straight.atom_count(), 11);
  EXPECT_EQ(straight.segment_count(), 10);
  EXPECT_EQ(straight.joints.size(), 9u);
  double mass = 0;
  for (const double m : straight.mass) mass += m;
  EXPECT_NEAR(mass, 10 * tube_stiffness(artery_wall(), 2.0).mass_per_mm, 1e-12);
  // A Y of 3 branches of 6 points: 3 x 4 interior atoms + 4 nodes, the junction shared by 3 segments
  // joined pairwise at half stiffness each.
  const VesselChain y = build_vessel_chain(y_centerline(6, 1.0, 30, 1.0), {0, 0, 0}, artery_wall(), "t");
  EXPECT_EQ(y.atom_count(), 16);
  EXPECT_EQ(y.segment_count(), 15);
  int at_junction = 0;
  for (const VesselJoint& j : y.joints) {
    if (j.atom != 1) continue;
    ++at_junction;
    EXPECT_NEAR(j.bending, 0.5 * tube_stiffness(artery_wall(), 1.0).bending, 1e-9);
  }
  EXPECT_EQ(at_junction, 3);
  EXPECT_EQ(y.joints.size(), 3u * 4 + 3);
  ctsurg::Centerline bad = straight_centerline(4, 1.0, 1.0);
  bad.points[3] = bad.points[0];  // points 0 and 1 coincide
  EXPECT_THROW(build_vessel_chain(bad, {0, 0, 0}, artery_wall(), "t"), ctsurg::InputError);
}

// A cantilever: atoms 0..n-1 along x, 1 mm apart, radius 1 mm, wall 0.2 mm; atoms 0 and 1 fixed (a
// built-in end at atom 1), the beam from atom 1 to the tip, L = n - 2 mm.
struct Cantilever {
  VesselChain chain;
  std::unique_ptr<VesselDynamics> dyn;
  double length = 0;
  ChainStiffness k;
  explicit Cantilever(int n, const VesselDynamicsOptions& o = {}) {
    chain = build_vessel_chain(straight_centerline(n, 1.0, 1.0), {0, 0, 0}, artery_wall(), "t");
    dyn = std::make_unique<VesselDynamics>(chain, o);
    dyn->fix_atoms({atom(0), atom(1)});
    length = n - 2;
    k = tube_stiffness(artery_wall(), 1.0);
  }
  // The i-th atom along the branch (atoms are numbered nodes first, vessel_chain.h).
  int32_t atom(int i) const { return chain.branch_atoms[static_cast<size_t>(i)]; }
  int32_t tip() const { return chain.branch_atoms.back(); }
};

TEST(VesselDynamics, CantileverBendingMatchesBeamTheory) {
  for (const int n : {22, 42, 82}) {
    Cantilever c(n);
    const double p = 1.0;  // uN at the tip, along -z: a deflection of 1e-3 L
    c.dyn->force[3 * static_cast<size_t>(c.tip()) + 2] = -p;
    const int it = c.dyn->solve_static(30);
    EXPECT_LT(it, 30);
    const double l = c.length;
    const double bending = p * l * l * l / (3 * c.k.bending), shear = p * l / c.k.shear;
    const double deflection = -c.dyn->x[3 * static_cast<size_t>(c.tip()) + 2];
    // Timoshenko (bending + shear): the discrete rod's only error is the quadrature of the joints,
    // 1/(2 M^2) for M segments, and the geometric nonlinearity at 1e-3 L.
    EXPECT_NEAR(deflection / (bending + shear), 1.0, 0.002) << n << " atoms";
    // Euler-Bernoulli's P L^3 / (3 E I) alone: within 2 % once the tube is slender (L >= 40 r; shear
    // adds 2 % at L = 20 r).
    if (l >= 40) {
      EXPECT_NEAR(deflection / bending, 1.0, 0.02) << n << " atoms";
    }
    std::printf("cantilever %d atoms (L = %.0f mm): deflection %.6g mm, P L^3/(3EI) %.6g (%+.3f %%), + shear %.6g (%+.3f %%)\n", n,
                l, deflection, bending, 100 * (deflection / bending - 1), bending + shear,
                100 * (deflection / (bending + shear) - 1));
  }
}

TEST(VesselDynamics, CantileverStretchAndTwistMatchTheory) {
  Cantilever c(42);
  const double p = 100.0;  // uN along +x
  c.dyn->force[3 * static_cast<size_t>(c.tip())] = p;
  c.dyn->solve_static(30);
  const double stretch = c.dyn->x[3 * static_cast<size_t>(c.tip())] - (c.chain.atom_count() - 1);
  EXPECT_NEAR(stretch / (p * c.length / c.k.stretch), 1.0, 1e-3);
  std::printf("stretch: %.6g mm, P L/(EA) %.6g mm\n", stretch, p * c.length / c.k.stretch);

  Cantilever t(42);
  const double torque = 50.0;  // uN mm about +x on the tip segment
  const size_t tip_segment = static_cast<size_t>(t.chain.segment_count() - 1);
  t.dyn->torque[3 * tip_segment] = torque;
  t.dyn->solve_static(30);
  // The tip segment's frame is the rod's at its middle, L - 1/2 mm from the built-in end.
  const auto& q = t.dyn->q[tip_segment];
  const auto& q0 = t.chain.segment_rest_frame[tip_segment];
  const Quaternion rel = multiply(q, {q0[0], -q0[1], -q0[2], -q0[3]});
  const double angle = 2 * std::atan2(rel[1], rel[0]);  // about x
  const double expected = torque * (t.length - 0.5) / t.k.torsion;
  EXPECT_NEAR(angle / expected, 1.0, 2e-3);
  std::printf("twist: %.6g rad, T (L - h/2)/(GJ) %.6g rad, T L/(GJ) %.6g rad\n", angle, expected, torque * t.length / t.k.torsion);
}

TEST(VesselDynamics, DampedDynamicsSettlesToTheStaticDeflectionAtAFrameStep) {
  VesselDynamicsOptions o;
  o.dt = 1.0 / 60;
  o.mass_damping = 20;
  Cantilever dynamic(42, o), stat(42);
  for (Cantilever* c : {&dynamic, &stat}) c->dyn->force[3 * static_cast<size_t>(c->tip()) + 2] = -1.0;
  stat.dyn->solve_static(30);
  for (int i = 0; i < 120; ++i) dynamic.dyn->step();
  const size_t z = 3 * static_cast<size_t>(dynamic.tip()) + 2;
  EXPECT_NEAR(dynamic.dyn->x[z] / stat.dyn->x[z], 1.0, 0.01);
  EXPECT_LT(dynamic.dyn->kinetic_energy(), 1e-6 * dynamic.dyn->elastic_energy() + 1e-12);
}

TEST(VesselDynamics, ThousandsOfAtomsUnderGravityStayStableAtAFrameStep) {
  // A 2,000-atom vessel (1 mm apart) held at both ends sags under gravity: finite, bounded, settling.
  VesselDynamicsOptions o;
  o.dt = 1.0 / 60;
  o.mass_damping = 5;
  o.gravity = {0, 0, -9810};
  const VesselChain chain = build_vessel_chain(straight_centerline(2000, 1.0, 2.0), {0, 0, 0}, artery_wall(), "t");
  VesselDynamics dyn(chain, o);
  dyn.fix_atoms({chain.branch_atoms[0], chain.branch_atoms[1], chain.branch_atoms[1998], chain.branch_atoms[1999]});
  double previous = 0;
  for (int i = 0; i < 20; ++i) {
    dyn.step();
    for (const double c : dyn.x) ASSERT_TRUE(std::isfinite(c));
    previous = dyn.kinetic_energy();
  }
  double lowest = 0;
  for (size_t a = 0; a < 2000; ++a) lowest = std::min(lowest, dyn.x[3 * a + 2]);
  EXPECT_LT(lowest, -1.0);     // it sags
  EXPECT_GT(lowest, -2000.0);  // and does not fall through
  EXPECT_TRUE(std::isfinite(previous));
}

}  // namespace
