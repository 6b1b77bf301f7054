#include "ctsurg/sim/base/instrument.h"

#include "ctsurg/core/error.h"
#include "instrument_test_shapes.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace ctsurg::sim {
namespace {

using test::box_mesh;
using test::icosphere;

double box_distance(const std::array<double, 3>& p, const std::array<double, 3>& lo, const std::array<double, 3>& hi) {
  double outside = 0, inside = -1e300;
  for (size_t a = 0; a < 3; ++a) {
    const double d = std::max(lo[a] - p[a], p[a] - hi[a]);
    outside += std::pow(std::max(d, 0.0), 2);
    inside = std::max(inside, d);
  }
  return inside > 0 ? std::sqrt(outside) : inside;
}

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(SignedDistanceGrid, ExactForABoxAtEveryNode) {
  // The mesh is the box itself, so every node's value is the box's exact signed distance: a check of
  // the band, the sweeping (far nodes) and the sign (inside nodes) together. Round coordinates put
  // nodes on the box's faces and edges on grid rows, the case the row offset is for.
  const std::array<double, 3> lo{-3, -2, 0}, hi{5, 2, 12};
  const SignedDistanceGrid g = bake_signed_distance_grid(box_mesh(lo, hi), 0.5, 4);
  ASSERT_EQ(g.dims[0], 8 / 0.5 + 1 + 8);
  double worst = 0;
  int inside = 0;
  for (int32_t k = 0; k < g.dims[2]; ++k)
    for (int32_t j = 0; j < g.dims[1]; ++j)
      for (int32_t i = 0; i < g.dims[0]; ++i) {
        const std::array<double, 3> p{g.origin[0] + i * g.spacing, g.origin[1] + j * g.spacing, g.origin[2] + k * g.spacing};
        const double expected = box_distance(p, lo, hi);
        const float got = g.phi[static_cast<size_t>(i + g.dims[0] * (j + g.dims[1] * k))];
        worst = std::max(worst, std::abs(got - expected));
        inside += got < 0;
      }
  EXPECT_LT(worst, 1e-5);
  EXPECT_EQ(inside, 15 * 7 * 23);  // the nodes strictly inside: 15 x 7 x 23 of them
}

TEST(SignedDistanceGrid, SphereExactNearTheSurfaceCloseDeeper) {
  // A 5 mm icosphere (1,280 faces; within 0.023 mm of the sphere) against brute force over its faces:
  // within two cells of the surface the nodes hold the exact distance to the mesh; deeper, the
  // distance to a nearby face the sweep carried, within 3 % of the depth; the sign everywhere that of
  // the sphere's |p - c| - r (no node within the chord error of the surface is on this grid's rows).
  const TriangleMesh m = icosphere(5, 3, {1, 2, 3});
  const SignedDistanceGrid g = bake_signed_distance_grid(m, 0.4, 3);
  const size_t nf = m.faces.size() / 3;
  double worst = 0, worst_deep = 0;
  int wrong_sign = 0;
  for (int32_t k = 0; k < g.dims[2]; ++k)
    for (int32_t j = 0; j < g.dims[1]; ++j)
      for (int32_t i = 0; i < g.dims[0]; ++i) {
        const std::array<double, 3> p{g.origin[0] + i * g.spacing, g.origin[1] + j * g.spacing, g.origin[2] + k * g.spacing};
        double exact = 1e300;
        for (size_t t = 0; t < nf; ++t) {
          exact = std::min(exact, point_triangle_distance(p, &m.vertices[3 * m.faces[3 * t]], &m.vertices[3 * m.faces[3 * t + 1]],
                                                          &m.vertices[3 * m.faces[3 * t + 2]]));
        }
        const double got = g.phi[static_cast<size_t>(i + g.dims[0] * (j + g.dims[1] * k))];
        const double sphere = std::sqrt(std::pow(p[0] - 1, 2) + std::pow(p[1] - 2, 2) + std::pow(p[2] - 3, 2)) - 5;
        if (std::abs(sphere) > 0.03) wrong_sign += (got < 0) != (sphere < 0);
        if (exact < 2 * g.spacing) {
          worst = std::max(worst, std::abs(std::abs(got) - exact));
        } else {
          worst_deep = std::max(worst_deep, std::abs(std::abs(got) - exact) / exact);
        }
      }
  EXPECT_EQ(wrong_sign, 0);
  EXPECT_LT(worst, 1e-5);
  EXPECT_LT(worst_deep, 0.03);
}

TEST(Instrument, PushesPointsOutToTheSurfaceAtAnyPose) {
  // A 4 x 2 x 10 mm box instrument, turned 30 degrees about an oblique axis and moved: points inside
  // it end on its surface (within 0.4 of the grid spacing: the trilinear distance rounds the box's
  // edges by that much), points outside stay where they are.
  const std::array<double, 3> lo{-2, -1, 0}, hi{2, 1, 10};
  const Instrument ins = make_instrument(box_mesh(lo, hi), "box", 0.25);
  const Quaternion q = axis_angle_rotation({1, 2, 3}, 30, "test", "rotation");
  const std::array<double, 3> c{100, -50, 650};
  const InstrumentView v = instrument_view(ins, q, c);
  const auto r = rotation_matrix(q);
  int pushed = 0;
  for (double x = -3; x <= 3; x += 0.37)
    for (double y = -2; y <= 2; y += 0.29)
      for (double z = -1; z <= 11; z += 0.53) {
        const std::array<double, 3> body{x, y, z};
        double p[3];
        for (int a = 0; a < 3; ++a) p[a] = c[a] + r[3 * a] * x + r[3 * a + 1] * y + r[3 * a + 2] * z;
        const double before = box_distance(body, lo, hi);
        const double original[3] = {p[0], p[1], p[2]};
        const int moved = push_point_out_of_instrument(v, p);
        EXPECT_EQ(moved, before < 0 ? 1 : 0) << x << " " << y << " " << z;
        // The point's new body coordinates: on the box's surface.
        double b[3] = {0, 0, 0};
        for (int a = 0; a < 3; ++a) b[a] = r[a] * (p[0] - c[0]) + r[3 + a] * (p[1] - c[1]) + r[6 + a] * (p[2] - c[2]);
        const double after = box_distance({b[0], b[1], b[2]}, lo, hi);
        if (before < 0) {
          ++pushed;
          EXPECT_GT(after, -0.4 * 0.25) << x << " " << y << " " << z;
          EXPECT_LT(after, 0.3) << x << " " << y << " " << z;  // out, not thrown away
        } else {
          for (int a = 0; a < 3; ++a) EXPECT_EQ(p[a], original[a]);
        }
      }
  EXPECT_GT(pushed, 500);
}

TEST(Instrument, BundledInstrumentsLoad) {
  const auto dir = ctsurg::test::source_dir() / "data_samples" / "instruments";
  for (const char* name : {"probe_rod.stl", "scalpel.stl", "retractor_blade.obj", "forceps_jaw.ply"}) {
    SCOPED_TRACE(name);
    const auto ins = load_instrument(dir / name);
    EXPECT_GT(ins->volume_mm3, 0);
    EXPECT_GT(ins->size_mm, 10);
    // The tip (the origin) is on or near the surface, and a point 1 mm into the shaft is inside.
    const InstrumentView v = instrument_view(*ins, kIdentityRotation, {0, 0, 0});
    EXPECT_LT(std::abs(instrument_signed_distance(v, 0, 0, 0)), 0.5);
    EXPECT_LT(instrument_signed_distance(v, 0, 0, 5), 0);
  }
  // The rod's volume: a 2.5 mm cylinder of 77.5 mm and a hemisphere, less the facets' chords.
  const auto rod = load_instrument(dir / "probe_rod.stl");
  const double expected = M_PI * 2.5 * 2.5 * 77.5 + 2.0 / 3 * M_PI * std::pow(2.5, 3);
  EXPECT_NEAR(rod->volume_mm3, expected, 0.03 * expected);
}

TEST(Instrument, RefusesMeshesWithoutAnInside) {
  TriangleMesh open = box_mesh({0, 0, 0}, {10, 10, 10});
  open.faces.resize(open.faces.size() - 3);  // a hole
  EXPECT_NE(message_of([&] { checked_instrument_mesh(open, "open.stl"); }).find("not closed"), std::string::npos);
  TriangleMesh mixed = box_mesh({0, 0, 0}, {10, 10, 10});
  std::swap(mixed.faces[1], mixed.faces[2]);  // one face wound the other way
  EXPECT_NE(message_of([&] { checked_instrument_mesh(mixed, "mixed.stl"); }).find("consistently oriented"), std::string::npos);
  TriangleMesh degenerate = box_mesh({0, 0, 0}, {10, 10, 10});
  degenerate.vertices.insert(degenerate.vertices.end(), {5, 5, 0});  // a sliver face on the bottom's diagonal
  degenerate.faces.insert(degenerate.faces.end(), {0, 3, 8});
  EXPECT_NE(message_of([&] { checked_instrument_mesh(degenerate, "sliver.obj"); }).find("degenerate"), std::string::npos);
  EXPECT_NE(message_of([&] { checked_instrument_mesh(box_mesh({0, 0, 0}, {1000, 10, 10}), "huge.ply"); }).find("millimetres"),
            std::string::npos);
  EXPECT_NE(message_of([&] { checked_instrument_mesh(box_mesh({0, 0, 0}, {0.1, 0.1, 0.1}), "tiny.ply"); }).find("mm across"),
            std::string::npos);
  EXPECT_NE(message_of([&] { make_instrument(box_mesh({0, 0, 0}, {400, 10, 10}), "fine.stl", 0.01); }).find("spacing_mm"),
            std::string::npos);
  // Inward faces are flipped, not refused.
  TriangleMesh inward = box_mesh({0, 0, 0}, {10, 10, 10});
  for (size_t t = 0; t < inward.faces.size(); t += 3) std::swap(inward.faces[t + 1], inward.faces[t + 2]);
  std::string note;
  const TriangleMesh fixed = checked_instrument_mesh(inward, "inward.stl", [&](const std::string& s) { note = s; });
  EXPECT_EQ(fixed.faces, box_mesh({0, 0, 0}, {10, 10, 10}).faces);
  EXPECT_NE(note.find("flipped"), std::string::npos);
}

}  // namespace
}  // namespace ctsurg::sim
