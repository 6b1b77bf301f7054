// Tests for ctsurg/sim/fem/fem_tools.h on a 4 x 2 x 2 mm box of Kuhn tets (1 mm cells): the sphere
// selects the free nodes strictly inside it at their current positions; a grab captures once (at its
// centre now, or where it started for a quasi-static engine), holds the captured displacement plus the
// tool's travel, lets go for good when it stops; two grabs on one node leave it to the later one; a
// point force is shared equally and changes only when a force starts or ends; a sphere on empty space
// is an InputError naming the tool.
#include "ctsurg/sim/fem/fem_tools.h"

#include "ctsurg/core/error.h"
#include "fem_test_models.h"

#include <gtest/gtest.h>

#include <numeric>

namespace ctsurg::sim {
namespace {

FemModel tools_box() { return test::fem_box_model(FemLaw::linear, {4, 2, 2}, {4, 2, 2}); }

// The node at (x, y, z) mm.
int32_t node_at(const FemModel& m, double x, double y, double z) {
  for (int32_t i = 0; i < m.node_count(); ++i) {
    if (std::abs(m.nodes[3 * i] - x) < 1e-9 && std::abs(m.nodes[3 * i + 1] - y) < 1e-9 && std::abs(m.nodes[3 * i + 2] - z) < 1e-9) return i;
  }
  return -1;
}

ToolInput grab_at(const Vec3& centre, double radius, bool active = true) {
  ToolInput t;
  t.acts = ToolPrimitive::hold;
  t.label = "tools[0] (grab)";
  t.radius_mm = radius;
  t.active = active;
  t.centre = centre;
  t.start_centre = centre;
  return t;
}

TEST(FemTools, SphereSelectsTheFreeNodesStrictlyInsideAtTheirCurrentPositions) {
  const FemModel m = tools_box();
  std::vector<double> u(m.nodes.size(), 0.0);
  std::vector<uint8_t> fixed(static_cast<size_t>(m.node_count()), 0);
  // Radius 1 around (2, 1, 1): only the centre node (the 6 face neighbours are exactly at 1 mm).
  EXPECT_EQ(free_nodes_in_sphere(m, u, fixed, {2, 1, 1}, 1.0), std::vector<int32_t>{node_at(m, 2, 1, 1)});
  const auto seven = free_nodes_in_sphere(m, u, fixed, {2, 1, 1}, 1.01);
  EXPECT_EQ(seven.size(), 7u);
  EXPECT_TRUE(std::is_sorted(seven.begin(), seven.end()));
  // A wholly fixed node is never selected, one held in some axes is (tools move its free axes); a
  // displaced node is found where it is now.
  fixed[static_cast<size_t>(node_at(m, 2, 1, 1))] = kAllAxes;
  fixed[static_cast<size_t>(node_at(m, 3, 1, 1))] = 2;  // y held
  EXPECT_EQ(free_nodes_in_sphere(m, u, fixed, {2, 1, 1}, 1.01).size(), 6u);
  const int32_t corner = node_at(m, 0, 0, 0);
  u[3 * static_cast<size_t>(corner)] = -5;
  EXPECT_EQ(free_nodes_in_sphere(m, u, fixed, {-5, 0, 0}, 0.5), std::vector<int32_t>{corner});
  EXPECT_THROW(free_nodes_in_sphere(m, std::vector<double>(3), fixed, {0, 0, 0}, 1), InputError);
}

TEST(FemTools, GrabHoldsTheCapturedDisplacementPlusTheTravelAndLetsGoForGood) {
  const FemModel m = tools_box();
  std::vector<std::string> notes;
  FemToolHolds holds(m, std::vector<uint8_t>(static_cast<size_t>(m.node_count()), 0), "s.yaml",
                     [&](const std::string& n) { notes.push_back(n); });
  std::vector<double> u(m.nodes.size(), 0.0);
  const int32_t tip = node_at(m, 4, 1, 1);
  u[3 * static_cast<size_t>(tip) + 2] = 0.25;  // the tip already moved up when the grab starts
  std::vector<ToolInput> tools{grab_at({4, 1, 1.25}, 0.5)};
  std::vector<int32_t> nodes;
  std::vector<double> d;
  EXPECT_TRUE(holds.captures(tools));  // the caller fetches the current displacement for this update
  holds.update_grabs(tools, 0.1, u, false, nodes, d);
  EXPECT_FALSE(holds.captures(tools));
  ASSERT_EQ(nodes, std::vector<int32_t>{tip});
  EXPECT_EQ(d, (std::vector<double>{0, 0, 0.25}));
  EXPECT_TRUE(holds.engaged(0));
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_EQ(notes[0], "tools[0] (grab): grabbed 1 nodes at t = 0.100000 s");
  // The tool moves 3 mm in x: the node follows, from its captured displacement; later displacements of
  // the model do not change what the grab holds.
  tools[0].centre = {7, 1, 1.25};
  u.assign(u.size(), 9.0);
  holds.update_grabs(tools, 0.2, u, false, nodes, d);
  EXPECT_EQ(nodes, std::vector<int32_t>{tip});
  EXPECT_EQ(d, (std::vector<double>{3, 0, 0.25}));
  // Released when inactive, and never captures again.
  tools[0].active = false;
  holds.update_grabs(tools, 0.3, u, false, nodes, d);
  EXPECT_TRUE(nodes.empty());
  EXPECT_FALSE(holds.engaged(0));
  tools[0].active = true;
  EXPECT_FALSE(holds.captures(tools));
  holds.update_grabs(tools, 0.4, u, false, nodes, d);
  EXPECT_TRUE(nodes.empty());
  EXPECT_EQ(notes.size(), 1u);
}

TEST(FemTools, QuasiStaticCaptureIsWhereAndWhenTheToolStarted) {
  const FemModel m = tools_box();
  FemToolHolds holds(m, std::vector<uint8_t>(static_cast<size_t>(m.node_count()), 0), "s.yaml");
  const std::vector<double> u(m.nodes.size(), 0.0);
  ToolInput g = grab_at({3, 1, 1}, 0.2);
  g.start_s = 0.05;
  g.start_centre = {4, 1, 1};  // it started at the tip and has moved 1 mm since
  std::vector<int32_t> nodes;
  std::vector<double> d;
  holds.update_grabs({g}, 0.1, u, true, nodes, d);
  EXPECT_EQ(nodes, std::vector<int32_t>{node_at(m, 4, 1, 1)});
  EXPECT_EQ(d, (std::vector<double>{-1, 0, 0}));
}

TEST(FemTools, ANodeTwoGrabsHoldFollowsTheLaterOne) {
  const FemModel m = tools_box();
  FemToolHolds holds(m, std::vector<uint8_t>(static_cast<size_t>(m.node_count()), 0), "s.yaml");
  const std::vector<double> u(m.nodes.size(), 0.0);
  ToolInput a = grab_at({2, 1, 1}, 1.01), b = grab_at({3, 1, 1}, 1.01);
  std::vector<ToolInput> tools{a, b};
  std::vector<int32_t> nodes;
  std::vector<double> d;
  holds.update_grabs(tools, 0, u, false, nodes, d);
  tools[1].centre = {3, 1, 3};  // b lifts by 2 mm; a stays
  holds.update_grabs(tools, 0.1, u, false, nodes, d);
  // a holds 7 nodes, b 7, sharing (2, 1, 1) and (3, 1, 1): 12 distinct, the shared ones lifted.
  ASSERT_EQ(nodes.size(), 12u);
  for (const int32_t shared : {node_at(m, 2, 1, 1), node_at(m, 3, 1, 1)}) {
    const auto it = std::find(nodes.begin(), nodes.end(), shared);
    ASSERT_NE(it, nodes.end());
    EXPECT_EQ(d[3 * static_cast<size_t>(it - nodes.begin()) + 2], 2.0);
  }
  EXPECT_EQ(d[2], 0.0);  // a's first node, not shared with b, stays
}

TEST(FemTools, ForceIsSharedEquallyAndChangesOnlyWhenItStartsOrEnds) {
  const FemModel m = tools_box();
  std::vector<uint8_t> fixed(static_cast<size_t>(m.node_count()), 0);
  fixed[static_cast<size_t>(node_at(m, 4, 1, 1))] = kAllAxes;
  FemToolHolds holds(m, fixed, "s.yaml");
  const std::vector<double> u(m.nodes.size(), 0.0);
  ToolInput f = grab_at({4, 1, 1}, 1.01);
  f.acts = ToolPrimitive::load;
  f.label = "tools[0] (force)";
  f.force_n = {0, 0, 0.5};
  EXPECT_TRUE(holds.update_forces({f}, u, false));
  const auto& forces = holds.nodal_forces();
  ASSERT_EQ(forces.size(), m.nodes.size());
  double total = 0;
  int loaded = 0;
  for (size_t i = 0; i < forces.size(); i += 3) {
    total += forces[i + 2];
    if (forces[i + 2] != 0) ++loaded;
    EXPECT_EQ(forces[i], 0.0);
  }
  EXPECT_EQ(loaded, 5);  // the 6 face neighbours of (4, 1, 1) inside the box (5), the fixed centre left out
  EXPECT_NEAR(total, 0.5e6, 1e-6);  // N -> uN
  // Its load on the tissue (tool_load): the force it applies, with no reactions needed, and its moment
  // about the centre: the five loaded neighbours sit symmetrically around it but for the missing +x one,
  // so only the -x neighbour's z force has an arm (about y).
  std::array<double, 6> load{};
  ASSERT_TRUE(holds.load(0, u, nullptr, load));
  EXPECT_NEAR(load[2], 0.5, 1e-12);
  EXPECT_NEAR(load[0], 0.0, 1e-12);
  EXPECT_NEAR(load[4], 0.1, 1e-12);  // r = (-1, 0, 0) x f = (0, 0, 0.1): r_z f_x - r_x f_z = 0.1 N mm
  EXPECT_FALSE(holds.update_forces({f}, u, false));
  f.active = false;
  EXPECT_TRUE(holds.update_forces({f}, u, false));
  EXPECT_TRUE(holds.nodal_forces().empty());
  EXPECT_FALSE(holds.engaged(0));
}

// A node held in some axes takes the force's other components: a neighbour held in z (a roller) is
// captured, and the z force is shared by the four nodes free in z, the total kept.
TEST(FemTools, ForceActsOnTheFreeAxesOfAPartlyHeldNode) {
  const FemModel m = tools_box();
  std::vector<uint8_t> fixed(static_cast<size_t>(m.node_count()), 0);
  fixed[static_cast<size_t>(node_at(m, 4, 1, 1))] = kAllAxes;
  const int32_t roller = node_at(m, 3, 1, 1);
  fixed[static_cast<size_t>(roller)] = 4;  // z held
  FemToolHolds holds(m, fixed, "s.yaml");
  ToolInput f = grab_at({4, 1, 1}, 1.01);
  f.acts = ToolPrimitive::load;
  f.label = "tools[0] (force)";
  f.force_n = {0.3, 0, 0.5};
  EXPECT_TRUE(holds.update_forces({f}, std::vector<double>(m.nodes.size(), 0.0), false));
  EXPECT_EQ(holds.held_nodes(0).size(), 5u);  // the roller too
  const auto& forces = holds.nodal_forces();
  EXPECT_EQ(forces[3 * static_cast<size_t>(roller) + 2], 0.0);
  EXPECT_DOUBLE_EQ(forces[3 * static_cast<size_t>(roller)], 0.3e6 / 5);  // x is free: its share
  double z = 0;
  for (const int32_t n : holds.held_nodes(0))
    if (n != roller) {
      EXPECT_DOUBLE_EQ(forces[3 * static_cast<size_t>(n) + 2], 0.5e6 / 4);
      z += forces[3 * static_cast<size_t>(n) + 2];
    }
  EXPECT_NEAR(z, 0.5e6, 1e-6);
}

TEST(FemTools, SphereOnEmptySpaceIsAnInputErrorNamingTheTool) {
  const FemModel m = tools_box();
  FemToolHolds holds(m, std::vector<uint8_t>(static_cast<size_t>(m.node_count()), 0), "s.yaml");
  const std::vector<double> u(m.nodes.size(), 0.0);
  std::vector<int32_t> nodes;
  std::vector<double> d;
  try {
    holds.update_grabs({grab_at({50, 50, 50}, 1)}, 0.25, u, false, nodes, d);
    ADD_FAILURE() << "a grab on empty space was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "s.yaml");
    EXPECT_EQ(e.field(), "tools[0] (grab)");
    EXPECT_NE(e.problem().find("grabs no free node at t = 0.250000 s"), std::string::npos) << e.problem();
  }
  ToolInput f = grab_at({50, 50, 50}, 1);
  f.acts = ToolPrimitive::load;
  EXPECT_THROW(holds.update_forces({f}, u, false), InputError);
}

}  // namespace
}  // namespace ctsurg::sim
