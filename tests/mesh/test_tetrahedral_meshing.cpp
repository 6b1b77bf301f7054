// Tests for mesh/include/ctsurg/mesh/tetrahedral_meshing.h on hand-made label lattices: a ball's
// volume against the analytic one, positive tets, a closed outward-oriented boundary consistent
// with the tets on each side, no slivers, two labels with a conforming interface, mirrored and
// tilted lattices, determinism, the size estimate and bad input. Coarse balls (a few thousand tets)
// keep each test fast, also under the sanitizers.
#include "ctsurg/mesh/tetrahedral_meshing.h"

#include "ctsurg/core/error.h"
#include "ctsurg/mesh/tet_mesh_quality.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <set>

namespace {

using ctsurg::TetMesh;
using Eigen::Vector3d;

constexpr double kRadius = 8.0;  // mm

// A lattice of 0.5 mm voxels around a ball of radius `r` centred at index `centre`; voxels inside
// `inner_r` (when > 0) get label 2, the rest of the ball label 1.
ctsurg::Volume<uint16_t> ball(const ctsurg::ImageGeometry& g, double r, double inner_r = 0.0) {
  ctsurg::Volume<uint16_t> v(g, 0);
  const Vector3d centre = 0.5 * Vector3d(double(g.dims[0] - 1), double(g.dims[1] - 1), double(g.dims[2] - 1));
  for (int64_t k = 0; k < g.dims[2]; ++k)
    for (int64_t j = 0; j < g.dims[1]; ++j)
      for (int64_t i = 0; i < g.dims[0]; ++i) {
        // Distance in mm in the lattice's own (index x spacing) frame, so the ball is a ball for any
        // direction matrix.
        const Vector3d d = (Vector3d(double(i), double(j), double(k)) - centre).cwiseProduct(g.spacing);
        const double n = d.norm();
        v(i, j, k) = n <= inner_r ? 2 : n <= r ? 1 : 0;
      }
  return v;
}

ctsurg::ImageGeometry lattice(Eigen::Matrix3d direction = Eigen::Matrix3d::Identity()) {
  ctsurg::ImageGeometry g;
  g.dims = {41, 39, 37};
  g.spacing = Vector3d(0.5, 0.5, 0.5);
  g.origin = Vector3d(-30.0, 12.0, 150.0);
  g.direction = direction;
  return g;
}

ctsurg::TetMeshingOptions coarse() {
  ctsurg::TetMeshingOptions o;
  o.cell_size_mm = 3.0;
  o.facet_size_mm = 1.5;
  o.facet_distance_mm = 0.3;
  return o;
}

Vector3d node(const TetMesh& m, int32_t i) {
  const auto k = static_cast<std::size_t>(i);
  return {m.nodes[3 * k], m.nodes[3 * k + 1], m.nodes[3 * k + 2]};
}

// Volume enclosed by the boundary faces whose (inside, outside) labels match, divergence theorem.
double enclosed_volume(const TetMesh& m, uint16_t inside, uint16_t outside) {
  double v = 0.0;
  for (int64_t f = 0; f < m.boundary_face_count(); ++f) {
    const auto k = static_cast<std::size_t>(f);
    if (m.face_labels[2 * k] != inside || m.face_labels[2 * k + 1] != outside) continue;
    const int32_t* t = &m.boundary_faces[3 * k];
    v += node(m, t[0]).dot(node(m, t[1]).cross(node(m, t[2]))) / 6.0;
  }
  return v;
}

// Every directed edge of the faces with labels (inside, outside) is used once and its reverse once.
bool closed_and_oriented(const TetMesh& m, uint16_t inside, uint16_t outside) {
  std::map<std::pair<int32_t, int32_t>, int> directed;
  for (int64_t f = 0; f < m.boundary_face_count(); ++f) {
    const auto k = static_cast<std::size_t>(f);
    if (m.face_labels[2 * k] != inside || m.face_labels[2 * k + 1] != outside) continue;
    const int32_t* t = &m.boundary_faces[3 * k];
    for (int c = 0; c < 3; ++c) ++directed[{t[c], t[(c + 1) % 3]}];
  }
  if (directed.empty()) return false;
  for (const auto& [e, n] : directed)
    if (n != 1 || !directed.count({e.second, e.first})) return false;
  return true;
}

// Each boundary face is a face of a tet of its inside label, whose fourth node lies behind the
// face's normal, and (unless outside is 0) of a tet of its outside label in front of it; no face
// between two tets of the same label is reported, and every face with a single tet is reported.
std::string boundary_problem(const TetMesh& m) {
  std::map<std::array<int32_t, 3>, std::vector<std::pair<int64_t, int32_t>>> tets_of_face;  // sorted face -> (tet, opposite)
  for (int64_t t = 0; t < m.tet_count(); ++t) {
    const int32_t* c = &m.tets[static_cast<std::size_t>(4 * t)];
    for (int i = 0; i < 4; ++i) {
      std::array<int32_t, 3> f{c[(i + 1) % 4], c[(i + 2) % 4], c[(i + 3) % 4]};
      std::sort(f.begin(), f.end());
      tets_of_face[f].push_back({t, c[i]});
    }
  }
  std::set<std::array<int32_t, 3>> reported;
  for (int64_t f = 0; f < m.boundary_face_count(); ++f) {
    const auto k = static_cast<std::size_t>(f);
    const int32_t* t = &m.boundary_faces[3 * k];
    std::array<int32_t, 3> key{t[0], t[1], t[2]};
    std::sort(key.begin(), key.end());
    if (!reported.insert(key).second) return "face reported twice";
    const auto it = tets_of_face.find(key);
    if (it == tets_of_face.end()) return "boundary face is not a tet face";
    const Vector3d n = (node(m, t[1]) - node(m, t[0])).cross(node(m, t[2]) - node(m, t[0]));
    const uint16_t in = m.face_labels[2 * k], out = m.face_labels[2 * k + 1];
    if (in == 0 || in == out) return "bad face labels";
    bool saw_in = false, saw_out = out == 0;
    for (const auto& [tet, opposite] : it->second) {
      const uint16_t l = m.tet_labels[static_cast<std::size_t>(tet)];
      const double side = n.dot(node(m, opposite) - node(m, t[0]));
      if (l == in && side < 0) saw_in = true;
      else if (l == out && side > 0) saw_out = true;
      else return "tet of label " + std::to_string(l) + " on the wrong side of a (" + std::to_string(in) + ", " +
                  std::to_string(out) + ") face";
    }
    if (out == 0 && it->second.size() != 1) return "skin face with two tets";
    if (!saw_in || !saw_out) return "face missing a tet on one side";
  }
  for (const auto& [f, tets] : tets_of_face) {
    const bool boundary = tets.size() == 1 || m.tet_labels[static_cast<std::size_t>(tets[0].first)] !=
                                                  m.tet_labels[static_cast<std::size_t>(tets[1].first)];
    if (boundary != (reported.count(f) > 0)) return boundary ? "unreported boundary face" : "interior face reported";
  }
  return "";
}

double label_volume(const TetMesh& m, uint16_t label) {
  double v = 0.0;
  for (int64_t t = 0; t < m.tet_count(); ++t) {
    if (m.tet_labels[static_cast<std::size_t>(t)] != label) continue;
    const int32_t* c = &m.tets[static_cast<std::size_t>(4 * t)];
    v += ctsurg::tet_signed_volume(node(m, c[0]), node(m, c[1]), node(m, c[2]), node(m, c[3]));
  }
  return v;
}

int64_t positive_tets(const TetMesh& m) {
  int64_t n = 0;
  for (int64_t t = 0; t < m.tet_count(); ++t) {
    const int32_t* c = &m.tets[static_cast<std::size_t>(4 * t)];
    n += ctsurg::tet_signed_volume(node(m, c[0]), node(m, c[1]), node(m, c[2]), node(m, c[3])) > 0.0;
  }
  return n;
}

const double kBall = 4.0 / 3.0 * std::numbers::pi * std::pow(kRadius, 3);

TEST(TetrahedralMeshing, BallVolumePositiveTetsClosedBoundaryNoSlivers) {
  const auto labels = ball(lattice(), kRadius);
  const TetMesh m = ctsurg::tetrahedral_mesh(labels, coarse(), "ball");
  EXPECT_GT(m.tet_count(), 300);
  EXPECT_LT(m.tet_count(), 20000);
  EXPECT_EQ(positive_tets(m), m.tet_count());
  EXPECT_EQ(m.quality.inverted, 0);
  EXPECT_EQ(m.quality.slivers, 0) << "min dihedral " << m.quality.min_dihedral_deg;
  EXPECT_GE(m.quality.min_dihedral_deg, 10.0);
  EXPECT_LE(m.quality.max_dihedral_deg, 170.0);
  // Volume: the analytic ball within 4 % (the voxel staircase smoothed by Mesh_3), and the sum of
  // tet volumes equal to the volume the boundary encloses (outward orientation).
  EXPECT_NEAR(m.quality.volume_mm3, kBall, 0.04 * kBall);
  EXPECT_NEAR(m.mask_volume_mm3, kBall, 0.04 * kBall);
  EXPECT_NEAR(enclosed_volume(m, 1, 0), m.quality.volume_mm3, 1e-9 * kBall);
  EXPECT_TRUE(closed_and_oriented(m, 1, 0));
  EXPECT_EQ(boundary_problem(m), "");
  EXPECT_TRUE(std::all_of(m.tet_labels.begin(), m.tet_labels.end(), [](uint16_t l) { return l == 1; }));
  // Nodes where the ball is, in LPS mm: centre = origin + index centre (identity direction).
  const Vector3d centre = lattice().index_to_world(Vector3d(20.0, 19.0, 18.0));
  double rmax = 0.0;
  for (int32_t v = 0; v < m.node_count(); ++v) rmax = std::max(rmax, (node(m, v) - centre).norm());
  EXPECT_NEAR(rmax, kRadius, 1.0);
  // Every node is used by a tet.
  std::vector<bool> used(static_cast<std::size_t>(m.node_count()), false);
  for (const int32_t i : m.tets) used[static_cast<std::size_t>(i)] = true;
  EXPECT_TRUE(std::all_of(used.begin(), used.end(), [](bool b) { return b; }));
}

TEST(TetrahedralMeshing, TwoLabelsShareAConformingInterface) {
  const double inner = 4.5;
  const auto labels = ball(lattice(), kRadius, inner);
  auto o = coarse();
  const TetMesh m = ctsurg::tetrahedral_mesh(labels, o, "two balls");
  EXPECT_EQ(positive_tets(m), m.tet_count());
  EXPECT_EQ(m.quality.slivers, 0) << "min dihedral " << m.quality.min_dihedral_deg;
  const double vin = 4.0 / 3.0 * std::numbers::pi * std::pow(inner, 3);
  EXPECT_NEAR(label_volume(m, 2), vin, 0.1 * vin);
  EXPECT_NEAR(label_volume(m, 1) + label_volume(m, 2), kBall, 0.04 * kBall);
  // The skin encloses both; the interface (1 inside, 2 outside) points into the inner ball, so it
  // encloses minus the inner volume.
  EXPECT_TRUE(closed_and_oriented(m, 1, 0));
  EXPECT_TRUE(closed_and_oriented(m, 1, 2));
  EXPECT_NEAR(enclosed_volume(m, 1, 0), m.quality.volume_mm3, 1e-9 * kBall);
  EXPECT_NEAR(enclosed_volume(m, 1, 2), -label_volume(m, 2), 1e-9 * kBall);
  EXPECT_EQ(boundary_problem(m), "");

  // Only label 2: a single ball of the inner size.
  o.labels = {2};
  const TetMesh only2 = ctsurg::tetrahedral_mesh(labels, o, "two balls");
  EXPECT_TRUE(std::all_of(only2.tet_labels.begin(), only2.tet_labels.end(), [](uint16_t l) { return l == 2; }));
  EXPECT_NEAR(only2.quality.volume_mm3, vin, 0.1 * vin);
  EXPECT_TRUE(closed_and_oriented(only2, 2, 0));
}

TEST(TetrahedralMeshing, MirroredAndTiltedLatticesKeepPositiveTetsInWorldSpace) {
  const Eigen::Matrix3d mirror = Eigen::Vector3d(-1.0, 1.0, 1.0).asDiagonal();
  const Eigen::Matrix3d tilt = Eigen::AngleAxisd(0.4, Vector3d(1.0, 2.0, 0.5).normalized()).toRotationMatrix() * mirror;
  const TetMesh reference = ctsurg::tetrahedral_mesh(ball(lattice(), kRadius), coarse(), "ball");
  for (const Eigen::Matrix3d& d : {mirror, tilt}) {
    const auto g = lattice(d);
    const TetMesh m = ctsurg::tetrahedral_mesh(ball(g, kRadius), coarse(), "ball");
    EXPECT_EQ(positive_tets(m), m.tet_count());
    EXPECT_EQ(m.quality.inverted, 0);
    EXPECT_NEAR(m.quality.volume_mm3, reference.quality.volume_mm3, 1e-6 * kBall);
    EXPECT_TRUE(closed_and_oriented(m, 1, 0));
    EXPECT_NEAR(enclosed_volume(m, 1, 0), m.quality.volume_mm3, 1e-9 * kBall);
    // The same mesh, moved: each node is the reference node mapped through the other lattice.
    ASSERT_EQ(m.node_count(), reference.node_count());
    const auto ref_g = lattice();
    double worst = 0.0;
    for (int32_t v = 0; v < m.node_count(); ++v) {
      const Vector3d expected = g.index_to_world(ref_g.world_to_index(node(reference, v)));
      worst = std::max(worst, (node(m, v) - expected).norm());
    }
    EXPECT_LT(worst, 1e-9);
  }
}

TEST(TetrahedralMeshing, OdtAndLloydSmoothingKeepAValidMesh) {
  const auto labels = ball(lattice(), kRadius);
  for (const auto optimiser : {ctsurg::TetOptimiser::odt, ctsurg::TetOptimiser::lloyd}) {
    auto o = coarse();
    o.optimiser = optimiser;
    o.optimiser_iterations = 5;
    const TetMesh m = ctsurg::tetrahedral_mesh(labels, o, "ball");
    EXPECT_EQ(positive_tets(m), m.tet_count());
    EXPECT_EQ(m.quality.slivers, 0) << "min dihedral " << m.quality.min_dihedral_deg;
    EXPECT_NEAR(m.quality.volume_mm3, kBall, 0.05 * kBall);
    EXPECT_TRUE(closed_and_oriented(m, 1, 0));
    EXPECT_NE(m.criteria.find(optimiser == ctsurg::TetOptimiser::odt ? "\"odt\"" : "\"lloyd\""), std::string::npos);
  }
}

TEST(TetrahedralMeshing, AnisotropicSpacingStaysABall) {
  auto g = lattice();
  g.dims = {41, 39, 11};
  g.spacing = Vector3d(0.5, 0.5, 2.0);
  const TetMesh m = ctsurg::tetrahedral_mesh(ball(g, kRadius), coarse(), "ball");
  EXPECT_EQ(positive_tets(m), m.tet_count());
  EXPECT_NEAR(m.quality.volume_mm3, kBall, 0.06 * kBall);
  EXPECT_NEAR(m.quality.volume_mm3, m.mask_volume_mm3, 0.06 * m.mask_volume_mm3);
}

TEST(TetrahedralMeshing, SameSeedSameMeshOtherSeedStillValid) {
  const auto labels = ball(lattice(), kRadius);
  const TetMesh a = ctsurg::tetrahedral_mesh(labels, coarse(), "ball");
  const TetMesh b = ctsurg::tetrahedral_mesh(labels, coarse(), "ball");
  EXPECT_EQ(a.nodes, b.nodes);
  EXPECT_EQ(a.tets, b.tets);
  EXPECT_EQ(a.boundary_faces, b.boundary_faces);
  auto o = coarse();
  o.seed = 7;
  const TetMesh c = ctsurg::tetrahedral_mesh(labels, o, "ball");
  EXPECT_EQ(c.seed, 7u);
  EXPECT_EQ(positive_tets(c), c.tet_count());
  EXPECT_NEAR(c.quality.volume_mm3, a.quality.volume_mm3, 0.02 * kBall);
}

TEST(TetrahedralMeshing, EstimateBoundsTheTetCount) {
  const auto labels = ball(lattice(), kRadius);
  for (const double cell : {2.0, 3.0, 5.0}) {
    auto o = coarse();
    o.cell_size_mm = cell;
    o.facet_size_mm = cell;
    const TetMesh m = ctsurg::tetrahedral_mesh(labels, o, "ball");
    const int64_t estimate = ctsurg::estimate_tet_count(ctsurg::labelled_volume_mm3(labels, {}),
                                                        ctsurg::labelled_surface_area_mm2(labels, {}), o);
    EXPECT_GE(estimate, m.tet_count()) << "cell " << cell;
    EXPECT_LE(estimate, 10 * m.tet_count()) << "cell " << cell;
  }
  // Finer criteria, more tets expected (roughly with the cube of the size).
  auto o = coarse();
  o.cell_size_mm = o.facet_size_mm = 0.5;
  EXPECT_GT(ctsurg::estimate_tet_count(1e6, 0.0, o), 1'000'000);
}

TEST(TetrahedralMeshing, BadInput) {
  const auto labels = ball(lattice(), kRadius);
  ctsurg::Volume<uint16_t> empty(lattice(), 0);
  try {
    ctsurg::tetrahedral_mesh(empty, coarse(), "empty.h5: /mask");
    ADD_FAILURE() << "no error";
  } catch (const ctsurg::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("empty.h5: /mask"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("nothing to mesh"), std::string::npos) << e.what();
  }
  auto o = coarse();
  o.labels = {3, 4};
  try {
    ctsurg::tetrahedral_mesh(labels, o, "ball");
    ADD_FAILURE() << "no error";
  } catch (const ctsurg::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("label 3,4"), std::string::npos) << e.what();
  }
  const auto expect_bad_option = [&](auto change, const std::string& option) {
    auto bad = coarse();
    change(bad);
    try {
      ctsurg::validate_tet_meshing_options(bad);
      ADD_FAILURE() << "no error for " << option;
    } catch (const ctsurg::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(option), std::string::npos) << e.what();
    }
  };
  expect_bad_option([](auto& x) { x.cell_size_mm = 0.0; }, "--cell-size");
  expect_bad_option([](auto& x) { x.cell_size_mm = -1.0; }, "--cell-size");
  expect_bad_option([](auto& x) { x.facet_size_mm = std::nan(""); }, "--facet-size");
  expect_bad_option([](auto& x) { x.facet_distance_mm = 0.0; }, "--facet-distance");
  expect_bad_option([](auto& x) { x.radius_edge_ratio = 0.5; }, "--radius-edge");
  expect_bad_option([](auto& x) { x.facet_angle_deg = 45.0; }, "--facet-angle");
  expect_bad_option([](auto& x) { x.sliver_bound_deg = -1.0; }, "--sliver-bound");
  expect_bad_option([](auto& x) { x.optimiser_iterations = 0; }, "--optimiser-iterations");
}

}  // namespace
