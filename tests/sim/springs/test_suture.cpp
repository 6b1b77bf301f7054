// Tests for ctsurg/sim/springs/suture.h and the suture in the spring engine (spring_engine.h): the rest
// length follows its schedule; stitches attach to the nearest particles at rest and refuse a point off
// the tissue, two ends on one particle and ends too far apart; a stiffness that would make the explicit
// step unstable is refused, naming the field and a step to try; and on an 8 x 4 x 4 block of 2 mm cells
// cut through at x = 19 mm, whose free half was moved 3 mm away, four stitches close the gap to its
// rest value (2 mm) while the run stays stable; without them the gap stays open.
#include "ctsurg/sim/springs/suture.h"

#include "block_surface.h"
#include "ctsurg/core/error.h"
#include "ctsurg/sim/base/fixed_regions.h"
#include "ctsurg/sim/springs/spring_calibration.h"
#include "ctsurg/sim/springs/spring_engine.h"
#include "liver_block_engine.h"
#include "sim_test_models.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace ctsurg::sim {
namespace {

// The InputError's field from f(), or "(accepted)".
template <typename F>
std::string suture_field_of(F f, std::string* message = nullptr) {
  try {
    f();
  } catch (const InputError& e) {
    if (message) *message = e.what();
    return e.field();
  }
  return "(accepted)";
}

// The 8 x 4 x 4 block (cell centres x 12 .. 26, y -18 .. -12, z 32 .. 38 mm), liver springs, x < 13 fixed,
// with its surface.
SpringEngine block_engine() { return test::liver_block_engine(8, 4, 4, 13); }

// Cuts the block through at x = 19 (between the cell centres 18 and 20).
void cut_through(SpringEngine& e) {
  ToolInput blade;
  blade.acts = ToolPrimitive::separate;
  blade.label = "tools[0] (cut)";
  blade.blade_edge_mm = {0, 0, 40};
  blade.active = true;
  blade.sweeps = {{Vec3{19, -40, 35}, Vec3{19, 0, 35}}};
  ASSERT_TRUE(e.step({blade}, 1).stable);
}

// The gap across x = 19: the free half's smallest x less the fixed half's largest x (rest: 2 mm).
double gap(const SpringEngine& e) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  const auto& rest = e.rest_positions();
  for (int32_t i = 0; i < e.state().count(); ++i) {
    const double x = e.state().x[static_cast<size_t>(i)];
    if (rest[3 * static_cast<size_t>(i)] > 19) {
      lo = std::min(lo, x);
    } else {
      hi = std::max(hi, x);
    }
  }
  return lo - hi;
}

ToolInput suture(double start, double end, double target) {
  ToolInput t;
  t.acts = ToolPrimitive::stitch;
  t.label = "tools[1] (suture)";
  t.start_s = start;
  t.end_s = end;
  t.stitch_target_mm = target;
  t.active = true;
  // Four stitches across the cut near the block's corners, a little off the particles (snapped to them).
  for (const double y : {-17.8, -12.2}) {
    for (const double z : {32.2, 37.8}) {
      t.stitches.push_back({Vec3{18.3, y, z}, Vec3{19.7, y, z}});
      t.stitch_fields.push_back("tools[1].suture.stitches[" + std::to_string(t.stitches.size() - 1) + "]");
    }
  }
  return t;
}

}  // namespace

TEST(Suture, RestLengthFollowsItsSchedule) {
  EXPECT_DOUBLE_EQ(stitch_rest_length(10, 2, 1.0, 1.4, 0.5), 10);   // before the window: as placed
  EXPECT_DOUBLE_EQ(stitch_rest_length(10, 2, 1.0, 1.4, 1.0), 10);
  EXPECT_NEAR(stitch_rest_length(10, 2, 1.0, 1.4, 1.1), 8, 1e-12);   // linear
  EXPECT_NEAR(stitch_rest_length(10, 2, 1.0, 1.4, 1.3), 4, 1e-12);
  EXPECT_DOUBLE_EQ(stitch_rest_length(10, 2, 1.0, 1.4, 1.4), 2);
  EXPECT_DOUBLE_EQ(stitch_rest_length(10, 2, 1.0, 1.4, 9.0), 2);     // the knot holds
  EXPECT_DOUBLE_EQ(stitch_rest_length(3, 0, 0.0, 1.0, 0.5), 1.5);
}

TEST(Suture, StitchesAttachToTheNearestParticlesAtRestAndRefuseBadPoints) {
  // Three particles on the x axis: 0, 2 and 40 mm.
  const std::vector<Real> rest{0, 0, 0, 2, 0, 0, 40, 0, 0};
  ParticleState s(rest, {1, 1, 1});
  s.x[1] = 5;  // moved since: the stitch still joins the particle that was at x = 2, from where it is now
  std::vector<Stitch> st = attach_stitches({{Vec3{0.4, 0, 0}, Vec3{2.3, 0.5, 0}}}, {"f"}, rest, s, 3, "s.yaml");
  ASSERT_EQ(st.size(), 1u);
  EXPECT_EQ(st[0].a, 0);
  EXPECT_EQ(st[0].b, 1);
  EXPECT_NEAR(st[0].initial_length, 5, 1e-6);
  EXPECT_NEAR(st[0].offset_b[0], 0.3, 1e-6);
  EXPECT_NEAR(st[0].offset_b[1], 0.5, 1e-6);
  std::string message;
  EXPECT_EQ(suture_field_of([&] { attach_stitches({{Vec3{0, 0, 0}, Vec3{2, 9, 0}}}, {"tools[1].suture.stitches[0]"}, rest, s, 3, "s.yaml"); },
                     &message),
            "tools[1].suture.stitches[0].b");
  EXPECT_NE(message.find("s.yaml"), std::string::npos) << message;
  EXPECT_NE(message.find("from the nearest particle"), std::string::npos) << message;
  EXPECT_EQ(suture_field_of([&] { attach_stitches({{Vec3{0, 0, 0}, Vec3{0.5, 0, 0}}}, {"g"}, rest, s, 3, "s.yaml"); }, &message), "g");
  EXPECT_NE(message.find("same particle"), std::string::npos) << message;
  EXPECT_EQ(suture_field_of([&] { attach_stitches({{Vec3{0, 0, 0}, Vec3{40, 0, 0}}}, {"h"}, rest, s, 3, "s.yaml"); }, &message), "h");
  EXPECT_NE(message.find("at most 30 mm"), std::string::npos) << message;
}

TEST(Suture, StepLimitIsTheGershgorinBound) {
  EXPECT_NEAR(stitch_step_limit(2.0, 100, 100), std::sqrt(2.0) * std::sqrt(2.0 / 200), 1e-15);
  EXPECT_EQ(stitch_step_limit(0.0, 100, 100), std::numeric_limits<double>::infinity());
}

TEST(Suture, AnUnstableStiffnessIsRefusedWithAStepToTry) {
  SpringEngine e = block_engine();
  cut_through(e);
  ToolInput t = suture(0.0, 0.1, 2);
  t.stitch_stiffness_ratio = 100;  // 100 springs' worth on a particle with fewer than 18
  std::string message;
  EXPECT_EQ(suture_field_of([&] { e.step({ToolInput{}, t}, 1); }, &message), "tools[1] (suture).stiffness_ratio");
  EXPECT_NE(message.find("s.yaml"), std::string::npos) << message;
  EXPECT_NE(message.find("time.dt_s <="), std::string::npos) << message;
  // The ratio the message suggests is accepted.
  const size_t at = message.find("stiffness_ratio to <= ");
  ASSERT_NE(at, std::string::npos) << message;
  const double ratio = std::stod(message.substr(at + 22));
  EXPECT_GT(ratio, 1);
  EXPECT_LT(ratio, 100);
  SpringEngine f = block_engine();
  cut_through(f);
  t.stitch_stiffness_ratio = 0.95 * ratio;
  EXPECT_EQ(suture_field_of([&] { f.step({ToolInput{}, t}, 1); }), "(accepted)");
  // A stitch point 20 mm off the block.
  SpringEngine g = block_engine();
  ToolInput far = suture(0.0, 0.1, 2);
  far.stitches[2][1] = {19.7, -12.2, 58};
  EXPECT_EQ(suture_field_of([&] { g.step({ToolInput{}, far}, 1); }, &message), "tools[1].suture.stitches[2].b");
}

TEST(Suture, StitchesCloseACutBlockToItsRestGapAndStayStable) {
  for (const bool stitched : {false, true}) {
    SpringEngine e = block_engine();
    cut_through(e);
    ASSERT_EQ(e.metrics().springs_cut, 16 + 2 * 24);  // every spring across x = 19 (4 x 4 face, 2 x 3 x 4 x 2 edge)
    // Move the free half 3 mm away, at rest (previous positions moved too): the host engine steps its
    // state in place, so the test writes it there.
    ParticleState& s = const_cast<ParticleState&>(e.state());
    for (int32_t i = 0; i < s.count(); ++i) {
      const size_t k = static_cast<size_t>(i);
      if (e.rest_positions()[3 * k] > 19) {
        s.x[k] += 3;
        s.px[k] += 3;
      }
    }
    const double before = gap(e);
    EXPECT_NEAR(before, 5, 1e-4);
    const ToolInput t = suture(0.01, 0.21, 2.0);
    std::vector<double> lengths;
    while (e.time() < 0.6) {
      ToolInput in = t;
      in.active = e.time() + e.dt() >= t.start_s && e.time() + e.dt() < t.end_s;
      const std::vector<ToolInput> tools = stitched ? std::vector<ToolInput>{ToolInput{}, in} : std::vector<ToolInput>{};
      ASSERT_TRUE(e.step(tools, 1).stable);
      if (e.steps() % 200 == 0) {
        ASSERT_TRUE(e.check_stability().stable) << "t " << e.time();
      }
      if (stitched && std::abs(e.time() - 0.11) < 0.5 * e.dt()) {
        for (const auto& ends : e.stitches(1)) lengths.push_back(std::hypot(ends[1][0] - ends[0][0], ends[1][1] - ends[0][1], ends[1][2] - ends[0][2]));
      }
    }
    const double after = gap(e);
    if (!stitched) {
      EXPECT_NEAR(after, before, 1e-3);  // nothing joins the halves: the gap stays open
      continue;
    }
    // Halfway through tightening the stitches are shorter than placed (5 mm + the points' offsets) and
    // still longer than at the end.
    ASSERT_EQ(lengths.size(), 4u);
    for (const double l : lengths) {
      EXPECT_LT(l, 5.0);
      EXPECT_GT(l, 1.4);
    }
    EXPECT_NEAR(after, 2.0, 0.05) << "gap before " << before << " mm, after " << after << " mm";
    // Settled: the kinetic energy left is under 1e-6 of what the stitches stored when placed (four of
    // k (3 mm)^2 / 2, k the stiffest spring).
    EXPECT_LT(e.metrics().kinetic_energy, 1e-6 * 4 * 0.5 * e.stitch_unit_stiffness() * 9);
    const auto ends = e.stitches(1);
    ASSERT_EQ(ends.size(), 4u);
    for (const auto& st : ends) EXPECT_NEAR(std::hypot(st[1][0] - st[0][0], st[1][1] - st[0][1], st[1][2] - st[0][2]), 1.4, 0.05);
  }
}

}  // namespace ctsurg::sim
