// The tube surface (vessel_skinning.h): an undeformed straight or curved vessel's surface against the
// analytic tube (every vertex and face centre within half a 0.5 mm voxel of it), closed and outward
// (each directed edge once), the volume of the polygonal tube; eq. 15's spokes against
// rotation-minimising frames on a helix (the twist between neighbouring rings); a cut's caps.
#include "ctsurg/sim/vessel/vessel_chain.h"
#include "ctsurg/sim/vessel/vessel_frames.h"
#include "ctsurg/sim/vessel/vessel_skinning.h"
#include "vessel_test_centerlines.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>

namespace {

using namespace ctsurg::sim;
using namespace ctsurg::sim::test;

constexpr double kHalfVoxelMm = 0.25;  // half of a 0.5 mm CT voxel
constexpr double kPi = std::numbers::pi;

VesselWall wall() {
  VesselWall w;
  w.youngs_modulus_pa = 1e6;
  w.thickness_mm = 0.3;
  return w;
}

// Each directed edge exactly once: a closed, consistently oriented surface.
void expect_closed(const std::vector<uint32_t>& tri) {
  std::map<std::pair<uint32_t, uint32_t>, int> edges;
  for (size_t f = 0; f < tri.size(); f += 3)
    for (int k = 0; k < 3; ++k) ++edges[{tri[f + static_cast<size_t>(k)], tri[f + static_cast<size_t>((k + 1) % 3)]}];
  for (const auto& [e, n] : edges) {
    ASSERT_EQ(n, 1) << e.first << "->" << e.second;
    ASSERT_EQ(edges.count({e.second, e.first}), 1u) << e.first << "->" << e.second;
  }
}

double enclosed_volume(const std::vector<float>& v, const std::vector<uint32_t>& t) {
  double vol = 0;
  for (size_t f = 0; f < t.size(); f += 3) {
    const float* a = &v[3 * t[f]];
    const float* b = &v[3 * t[f + 1]];
    const float* c = &v[3 * t[f + 2]];
    vol += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0;
  }
  return vol;
}

// The largest |distance from the axis - r| over the vertices and the faces' centres.
template <typename Distance>
double worst_error(const std::vector<float>& v, const std::vector<uint32_t>& tri, int64_t caps, double r, Distance&& axis_distance) {
  double worst = 0;
  for (size_t i = 0; i < v.size(); i += 3) worst = std::max(worst, std::abs(axis_distance(v[i], v[i + 1], v[i + 2]) - r));
  for (size_t f = 0; f + 3 * static_cast<size_t>(caps) < tri.size(); f += 3) {
    double c[3] = {0, 0, 0};
    for (int k = 0; k < 3; ++k)
      for (int d = 0; d < 3; ++d) c[d] += v[3 * tri[f + static_cast<size_t>(k)] + static_cast<size_t>(d)] / 3.0;
    worst = std::max(worst, std::abs(axis_distance(c[0], c[1], c[2]) - r));
  }
  return worst;
}

TEST(VesselSkinning, StraightAndCurvedVesselsLieOnTheAnalyticTube) {
  for (const VesselSkinning mode : {VesselSkinning::rmf, VesselSkinning::spokes}) {
    const VesselChain straight = build_vessel_chain(straight_centerline(41, 1.0, 2.0, {5, -3, 7}), {0, 0, 0}, wall(), "t");
    const VesselSkin skin(straight, 16, mode);
    std::vector<float> v;
    skin.vertices(straight.rest, mode == VesselSkinning::rmf ? &straight.segment_rest_frame : nullptr, v);
    EXPECT_EQ(static_cast<int64_t>(v.size()), 3 * skin.vertex_count());
    const double e = worst_error(v, skin.triangles(), skin.cap_triangles(), 2.0, [](double, double y, double z) {
      return std::hypot(y + 3, z - 7);
    });
    EXPECT_LT(e, kHalfVoxelMm);
    expect_closed(skin.triangles());
    // The volume of a 16-gon prism of circumradius 2 over 40 mm.
    EXPECT_NEAR(enclosed_volume(v, skin.triangles()), 0.5 * 16 * 4 * std::sin(2 * kPi / 16) * 40, 1e-2);  // float vertices

    // A quarter circle of radius 20 mm, atoms 1 mm apart along it, radius 2 mm.
    const VesselChain arc = build_vessel_chain(arc_centerline(32, 20, 90, 2.0), {0, 0, 0}, wall(), "t");
    const VesselSkin arc_skin(arc, 16, mode);
    arc_skin.vertices(arc.rest, mode == VesselSkinning::rmf ? &arc.segment_rest_frame : nullptr, v);
    const double ea = worst_error(v, arc_skin.triangles(), arc_skin.cap_triangles(), 2.0, [](double x, double y, double z) {
      return std::hypot(std::hypot(x, z) - 20, y);
    });
    EXPECT_LT(ea, kHalfVoxelMm);
    expect_closed(arc_skin.triangles());
    std::printf("%s: straight tube within %.4f mm, arc within %.4f mm of the analytic surface\n",
                mode == VesselSkinning::rmf ? "rmf" : "spokes", e, ea);
  }
}

TEST(VesselSkinning, PaperSpokesTwistOnAHelixWhereRotationMinimisingFramesDoNot) {
  // A helix about x (radius 6 mm, pitch 12 mm): its tangent passes near z twice a turn, where eq. 15's
  // spoke (in xOy) swings round; the double-reflection frames turn only as the curve does.
  const double big_r = 6, pitch = 12, step = 0.15;  // rad per atom: about 1 mm apart
  const VesselChain helix = build_vessel_chain(branch_centerline(126, 1.5, [&](double s) {
                                                 const double a = s * step;
                                                 return std::array<double, 3>{pitch * a / (2 * kPi), big_r * std::cos(a), big_r * std::sin(a)};
                                               }),
                                               {0, 0, 0}, wall(), "t");
  std::vector<float> v;
  std::vector<double> spokes_rmf, spokes_paper;
  VesselSkin(helix, 16, VesselSkinning::rmf).vertices(helix.rest, nullptr, v, &spokes_rmf);
  VesselSkin(helix, 16, VesselSkinning::spokes).vertices(helix.rest, nullptr, v, &spokes_paper);
  const double rmf = max_spoke_turn_deg(helix, helix.rest, spokes_rmf);
  const double paper = max_spoke_turn_deg(helix, helix.rest, spokes_paper);
  std::printf("helix: largest turn between neighbouring rings: rmf %.4f deg, eq. 15 spokes %.2f deg\n", rmf, paper);
  EXPECT_LT(rmf, 0.05);
  EXPECT_GT(paper, 20.0);
  // The chain's own rest frames (rmf with frames) agree with the bare double reflection.
  std::vector<double> spokes_frames;
  VesselSkin(helix, 16, VesselSkinning::rmf).vertices(helix.rest, &helix.segment_rest_frame, v, &spokes_frames);
  EXPECT_LT(max_spoke_turn_deg(helix, helix.rest, spokes_frames), 1.0);
}

TEST(VesselSkinning, CutsAndJunctionsGiveClosedTubes) {
  const VesselChain y = build_vessel_chain(y_centerline(8, 1.0, 35, 1.0), {0, 0, 0}, wall(), "t");
  VesselSkin skin(y, 12, VesselSkinning::rmf);
  expect_closed(skin.triangles());
  EXPECT_EQ(skin.vertex_count(), 3 * 8 * 12);
  EXPECT_EQ(skin.cap_triangles(), 6 * 10);  // each branch capped at both ends
  std::vector<uint8_t> alive(static_cast<size_t>(y.segment_count()), 1);
  const size_t before = skin.triangles().size();
  alive[3] = 0;  // the trunk cut between its 4th and 5th atoms
  skin.update_topology(alive);
  expect_closed(skin.triangles());
  EXPECT_EQ(skin.triangles().size(), before + 3 * (2 * 10 - 2 * 12));
  EXPECT_EQ(skin.cap_triangles(), 8 * 10);
}

}  // namespace
