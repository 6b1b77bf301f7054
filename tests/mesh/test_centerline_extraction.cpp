// Tests for mesh/include/ctsurg/mesh/centerline_extraction.h on synthetic tubes rasterised with their
// staircase (a voxel is inside when its centre is within the radius of the axis): a straight tube at
// a slant (isotropic and anisotropic voxels), a quarter torus and a Y; the centerline against the true
// axis and radius, topology, noise, determinism and the refusals.
#include "ctsurg/mesh/centerline_extraction.h"

#include "ctsurg/core/error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <random>

namespace {

using Vec = Eigen::Vector3d;

// Distance from p to the segment [a, b]; `t_out`: p's parameter along it (0 at a, 1 at b, unclamped).
double segment_distance(const Vec& p, const Vec& a, const Vec& b, double* t_out = nullptr) {
  const Vec d = b - a;
  const double t = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
  if (t_out) *t_out = (p - a).dot(d) / d.squaredNorm();
  return (p - (a + t * d)).norm();
}

// A mask from an inside test in LPS mm (identity direction, origin `origin`).
ctsurg::Volume<uint8_t> rasterise(std::array<int64_t, 3> dims, const Vec& spacing, const std::function<bool(const Vec&)>& inside,
                                  const Vec& origin = Vec(-3.0, 2.0, 7.0)) {
  ctsurg::ImageGeometry g;
  g.dims = dims;
  g.spacing = spacing;
  g.origin = origin;
  ctsurg::Volume<uint8_t> m(g, 0);
  for (int64_t k = 0; k < dims[2]; ++k)
    for (int64_t j = 0; j < dims[1]; ++j)
      for (int64_t i = 0; i < dims[0]; ++i) m(i, j, k) = inside(g.index_to_world(Vec(double(i), double(j), double(k))));
  return m;
}

struct Accuracy {
  double mean_axis = 0.0, max_axis = 0.0, mean_radius_error = 0.0, max_radius_error = 0.0;
  int measured = 0;
};

// Centerline points farther than `exclude(p)` from the ends are compared with the true axis
// (`axis_distance`) and radius.
Accuracy measure(const ctsurg::Centerline& c, const std::function<double(const Vec&)>& axis_distance, double radius,
                 const std::function<bool(const Vec&)>& excluded) {
  Accuracy a;
  for (int64_t p = 0; p < c.point_count(); ++p) {
    const Vec x(c.points[static_cast<std::size_t>(3 * p)], c.points[static_cast<std::size_t>(3 * p + 1)],
                c.points[static_cast<std::size_t>(3 * p + 2)]);
    if (excluded(x)) continue;
    const double d = axis_distance(x), e = c.radius[static_cast<std::size_t>(p)] - radius;
    a.mean_axis += d;
    a.max_axis = std::max(a.max_axis, d);
    a.mean_radius_error += e;
    a.max_radius_error = std::max(a.max_radius_error, std::abs(e));
    ++a.measured;
  }
  if (a.measured) {
    a.mean_axis /= a.measured;
    a.mean_radius_error /= a.measured;
  }
  return a;
}

std::vector<int> node_degrees(const ctsurg::Centerline& c) {
  std::vector<int> d(static_cast<std::size_t>(c.node_count()), 0);
  for (const int32_t n : c.branch_nodes) ++d[static_cast<std::size_t>(n)];
  return d;
}

struct Straight {
  Vec a, b;
  double r;
};

// A slanted straight tube: its axis crosses voxel rows at an angle, so the mask is a staircase.
Straight straight_tube(double r) {
  const Vec origin(-3.0, 2.0, 7.0);
  return {origin + Vec(4.3, 5.2, 4.9), origin + Vec(40.1, 17.3, 14.6), r};
}

ctsurg::Volume<uint8_t> straight_mask(const Straight& s, const Vec& spacing) {
  const std::array<int64_t, 3> dims{static_cast<int64_t>(std::ceil(45.0 / spacing[0])), static_cast<int64_t>(std::ceil(23.0 / spacing[1])),
                                    static_cast<int64_t>(std::ceil(20.0 / spacing[2]))};
  return rasterise(dims, spacing, [&](const Vec& p) {
    double t = 0.0;
    const double d = segment_distance(p, s.a, s.b, &t);
    return t >= 0.0 && t <= 1.0 && d <= s.r;
  });
}

void expect_straight_accuracy(const Vec& spacing, double r) {
  const Straight s = straight_tube(r);
  const auto mask = straight_mask(s, spacing);
  const auto c = ctsurg::extract_centerline(mask, {}, "tube");
  ASSERT_EQ(c.branch_count(), 1);
  ASSERT_EQ(c.node_count(), 2);
  const double h = spacing.maxCoeff();
  // Away from the flat ends (within r + 1 voxel of them the medial axis turns into the caps).
  const auto a = measure(
      c, [&](const Vec& p) { return segment_distance(p, s.a, s.b); }, r,
      [&](const Vec& p) { return (p - s.a).norm() < r + h || (p - s.b).norm() < r + h; });
  ASSERT_GT(a.measured, 20);
  std::printf("straight tube r %.2f mm, spacing %.2f %.2f %.2f: axis mean %.3f max %.3f mm; radius error mean %+.3f max %.3f mm "
              "(%d points)\n",
              r, spacing[0], spacing[1], spacing[2], a.mean_axis, a.max_axis, a.mean_radius_error, a.max_radius_error, a.measured);
  EXPECT_LT(a.mean_axis, 0.3 * h);
  EXPECT_LT(a.max_axis, 1.0 * h);
  EXPECT_LT(std::abs(a.mean_radius_error), 0.25 * h);
  EXPECT_LT(a.max_radius_error, 0.5 * h);
  // The whole tube is covered: the centerline spans the axis to within the radius of its ends.
  const Vec first(c.nodes[0], c.nodes[1], c.nodes[2]), last(c.nodes[3], c.nodes[4], c.nodes[5]);
  const double span = (first - last).norm();
  EXPECT_GT(span, (s.b - s.a).norm() - 2.0 * (r + h));
}

TEST(CenterlineExtraction, StraightTubeFollowsTheAxisAndRadius) {
  for (const double r : {2.6, 4.0, 5.5}) expect_straight_accuracy(Vec(1.0, 1.0, 1.0), r);
}

TEST(CenterlineExtraction, AnisotropicVoxels) { expect_straight_accuracy(Vec(0.8, 0.8, 1.5), 4.2); }

// The radius correction is subtracted in voxels across the branch (1 mm here): the default (none) is
// unbiased on round tubes, half a voxel would make every radius half a voxel small.
TEST(CenterlineExtraction, RadiusCorrectionIsInVoxelsAcrossTheBranch) {
  const Straight s = straight_tube(4.0);
  const auto mask = straight_mask(s, Vec(1.0, 1.0, 1.0));
  ctsurg::CenterlineOptions half;
  half.radius_correction_voxels = 0.5;
  const auto a = ctsurg::extract_centerline(mask, {}, "tube"), b = ctsurg::extract_centerline(mask, half, "tube");
  ASSERT_EQ(a.points, b.points);
  for (std::size_t p = 0; p < a.radius.size(); ++p) EXPECT_NEAR(a.radius[p] - b.radius[p], 0.5, 1e-9) << p;
}

TEST(CenterlineExtraction, QuarterTorus) {
  const Vec centre(0.0, 2.0, 17.0);  // the torus' centre; its axis is z
  const double major = 16.0, minor = 3.7;
  const auto axis_distance = [&](const Vec& p) {
    const Vec q = p - centre;
    return std::hypot(std::hypot(q.x(), q.y()) - major, q.z());
  };
  const auto angle = [&](const Vec& p) { return std::atan2(p.y() - centre.y(), p.x() - centre.x()); };
  const auto mask = rasterise({26, 26, 14}, Vec(1.0, 1.0, 1.0), [&](const Vec& p) {
    const double a = angle(p);
    return a >= 0.0 && a <= std::numbers::pi / 2 && axis_distance(p) <= minor;
  }, Vec(-3.0, -1.0, 10.0));
  const auto c = ctsurg::extract_centerline(mask, {}, "torus");
  ASSERT_EQ(c.branch_count(), 1);
  const double margin = (minor + 1.0) / major;
  const auto a = measure(c, axis_distance, minor, [&](const Vec& p) {
    const double t = angle(p);
    return t < margin || t > std::numbers::pi / 2 - margin;
  });
  ASSERT_GT(a.measured, 10);
  std::printf("quarter torus R %.1f r %.1f: axis mean %.3f max %.3f mm; radius error mean %+.3f max %.3f mm (%d points)\n",
              major, minor, a.mean_axis, a.max_axis, a.mean_radius_error, a.max_radius_error, a.measured);
  EXPECT_LT(a.mean_axis, 0.3);
  EXPECT_LT(a.max_axis, 1.0);
  EXPECT_LT(std::abs(a.mean_radius_error), 0.25);
  EXPECT_LT(a.max_radius_error, 0.5);
}

// A Y: a trunk and two daughters meeting at J.
struct Y {
  Vec j, ends[3];
  double r = 3.2;
};

Y y_shape() {
  Y y;
  const Vec o(-3.0, 2.0, 7.0);
  y.j = o + Vec(18.2, 16.1, 9.6);
  y.ends[0] = o + Vec(3.9, 15.7, 9.1);
  y.ends[1] = o + Vec(35.4, 4.3, 8.2);
  y.ends[2] = o + Vec(34.8, 28.6, 11.3);
  return y;
}

double y_axis_distance(const Y& y, const Vec& p) {
  double d = 1e300;
  for (const Vec& e : y.ends) d = std::min(d, segment_distance(p, y.j, e));
  return d;
}

ctsurg::Volume<uint8_t> y_mask(const Y& y) {
  return rasterise({42, 34, 20}, Vec(1.0, 1.0, 1.0), [&](const Vec& p) { return y_axis_distance(y, p) <= y.r; });
}

TEST(CenterlineExtraction, BranchingYGivesThreeBranchesAndOneJunction) {
  const Y y = y_shape();
  const auto mask = y_mask(y);
  const auto c = ctsurg::extract_centerline(mask, {}, "y");
  ASSERT_EQ(c.branch_count(), 3);
  const auto deg = node_degrees(c);
  ASSERT_EQ(deg.size(), 4u);
  EXPECT_EQ(std::count(deg.begin(), deg.end(), 3), 1);
  EXPECT_EQ(std::count(deg.begin(), deg.end(), 1), 3);
  const auto a = measure(c, [&](const Vec& p) { return y_axis_distance(y, p); }, y.r, [&](const Vec& p) {
    bool near = (p - y.j).norm() < 2.0 * y.r;  // the medial axis of a union of tubes bends near the junction
    for (const Vec& e : y.ends) near = near || (p - e).norm() < y.r + 1.0;
    return near;
  });
  std::printf("Y r %.1f: axis mean %.3f max %.3f mm; radius error mean %+.3f max %.3f mm (%d points)\n", y.r, a.mean_axis,
              a.max_axis, a.mean_radius_error, a.max_radius_error, a.measured);
  EXPECT_LT(a.mean_axis, 0.3);
  EXPECT_LT(a.max_axis, 1.0);
  EXPECT_LT(std::abs(a.mean_radius_error), 0.25);
  EXPECT_LT(a.max_radius_error, 0.5);
  // The junction node lies near J.
  for (std::size_t n = 0; n < deg.size(); ++n) {
    if (deg[n] == 3) {
      EXPECT_LT((Vec(c.nodes[3 * n], c.nodes[3 * n + 1], c.nodes[3 * n + 2]) - y.j).norm(), 2.0 * y.r);
    }
  }
}

TEST(CenterlineExtraction, BoundaryNoiseAddsNoBranch) {
  const Y y = y_shape();
  auto mask = y_mask(y);
  const auto& g = mask.geometry;
  std::vector<int64_t> boundary;
  for (int64_t k = 1; k + 1 < g.dims[2]; ++k)
    for (int64_t j = 1; j + 1 < g.dims[1]; ++j)
      for (int64_t i = 1; i + 1 < g.dims[0]; ++i) {
        const uint8_t v = mask(i, j, k);
        if (mask(i - 1, j, k) != v || mask(i + 1, j, k) != v || mask(i, j - 1, k) != v || mask(i, j + 1, k) != v ||
            mask(i, j, k - 1) != v || mask(i, j, k + 1) != v) {
          boundary.push_back(g.flat_index(i, j, k));
        }
      }
  std::mt19937 rng(7);
  for (int n = 0; n < 40; ++n) {
    const int64_t v = boundary[std::uniform_int_distribution<std::size_t>(0, boundary.size() - 1)(rng)];
    mask.voxels[static_cast<std::size_t>(v)] ^= 1;
  }
  ctsurg::CenterlineOptions o;
  o.keep_largest_component = true;  // a flipped voxel may sit alone outside the tube
  const auto c = ctsurg::extract_centerline(mask, o, "noisy y");
  EXPECT_EQ(c.branch_count(), 3);
  EXPECT_EQ(c.node_count(), 4);
}

TEST(CenterlineExtraction, Deterministic) {
  const Y y = y_shape();
  const auto mask = y_mask(y);
  const auto a = ctsurg::extract_centerline(mask, {}, "y"), b = ctsurg::extract_centerline(mask, {}, "y");
  EXPECT_EQ(a.points, b.points);
  EXPECT_EQ(a.radius, b.radius);
  EXPECT_EQ(a.branch_nodes, b.branch_nodes);
}

std::string refusal(const ctsurg::Volume<uint8_t>& mask, const ctsurg::CenterlineOptions& o = {}) {
  try {
    (void)ctsurg::extract_centerline(mask, o, "m.nii");
  } catch (const ctsurg::InputError& e) {
    EXPECT_EQ(e.file(), "m.nii");
    EXPECT_EQ(e.field(), "mask");
    return e.problem();
  }
  ADD_FAILURE() << "not refused";
  return {};
}

TEST(CenterlineExtraction, RefusesEmptyPiecesLoopsAndBlobs) {
  const Vec one(1.0, 1.0, 1.0);
  EXPECT_NE(refusal(rasterise({8, 8, 8}, one, [](const Vec&) { return false; })).find("empty"), std::string::npos);

  // Two tubes: refused with the count and sizes, or the larger kept.
  const Vec o(-3.0, 2.0, 7.0);
  const auto two = rasterise({30, 20, 12}, one, [&](const Vec& p) {
    return segment_distance(p, o + Vec(3, 5, 6), o + Vec(26, 5, 6)) <= 2.5 || segment_distance(p, o + Vec(3, 14, 6), o + Vec(16, 14, 6)) <= 2.5;
  });
  const std::string pieces = refusal(two);
  EXPECT_NE(pieces.find("2 separate pieces"), std::string::npos) << pieces;
  ctsurg::CenterlineOptions keep;
  keep.keep_largest_component = true;
  const auto kept = ctsurg::extract_centerline(two, keep, "m.nii");
  EXPECT_EQ(kept.branch_count(), 1);
  EXPECT_GT(std::abs(kept.nodes[0] - kept.nodes[3]), 12.0);  // the long tube

  // A full torus: a loop, refused with where; cut at its thinnest point on request.
  const Vec centre(o + Vec(12.0, 12.0, 5.0));
  const auto ring = rasterise({25, 25, 11}, one, [&](const Vec& p) {
    const Vec q = p - centre;
    return std::hypot(std::hypot(q.x(), q.y()) - 8.0, q.z()) <= 2.6 + 0.4 * (q.x() > 0 ? q.x() / 8.0 : 0.0);
  });
  const std::string loop = refusal(ring);
  EXPECT_NE(loop.find("1 loop"), std::string::npos) << loop;
  EXPECT_NE(loop.find("LPS ("), std::string::npos) << loop;
  ctsurg::CenterlineOptions cut;
  cut.break_loops = true;
  const auto opened = ctsurg::extract_centerline(ring, cut, "m.nii");
  EXPECT_EQ(opened.branch_count(), 1);
  // Cut where the ring is thinnest (x < 0: the far side from the thickening).
  EXPECT_LT(opened.nodes[0], centre.x() + 1.0);

  // A ball: no tubular part.
  const auto ball = rasterise({15, 15, 15}, one, [&](const Vec& p) { return (p - (o + Vec(7, 7, 7))).norm() <= 5.5; });
  EXPECT_NE(refusal(ball).find("no tubular part"), std::string::npos);
}

TEST(CenterlineExtraction, OptionsAreChecked) {
  ctsurg::CenterlineOptions o;
  o.smoothing_iterations = -1;
  EXPECT_THROW(ctsurg::validate_centerline_options(o), ctsurg::InputError);
  o = {};
  o.min_length_factor = 0.0;
  EXPECT_THROW(ctsurg::validate_centerline_options(o), ctsurg::InputError);
  o = {};
  o.spur_length_factor = std::nan("");
  EXPECT_THROW(ctsurg::validate_centerline_options(o), ctsurg::InputError);
}

}  // namespace
