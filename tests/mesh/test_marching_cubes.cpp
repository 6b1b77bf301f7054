// Tests for mesh/include/ctsurg/mesh/marching_cubes.h: closed, consistently oriented 2-manifolds on
// every single-cube case and on random fields (several sizes, many seeds, oblique and mirrored
// lattices), convergence of volume and area on ctsurg's analytic phantoms, thread-count
// independence, and the grid tie (trilinear weights, nearest inside node).
#include "ctsurg/mesh/marching_cubes.h"

#include "ctsurg/core/error.h"
#include "ctsurg/preprocess/synthetic_phantom.h"
#include "surface_checks.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <set>
#include <tuple>

namespace {

using ctsurg::SurfaceMesh;
using ctsurg::Volume;

using ctsurg::test::enclosed_volume;
using ctsurg::test::manifold_problem;
using ctsurg::test::vertex;
double area(const SurfaceMesh& m) { return ctsurg::test::surface_area(m); }

bool unique_positions(const SurfaceMesh& m) {
  std::set<std::tuple<float, float, float>> seen;
  for (int64_t v = 0; v < m.vertex_count(); ++v) {
    const std::size_t i = static_cast<std::size_t>(3 * v);
    if (!seen.insert({m.vertices[i], m.vertices[i + 1], m.vertices[i + 2]}).second) return false;
  }
  return true;
}

ctsurg::ImageGeometry cube_geometry(int64_t n) {
  ctsurg::ImageGeometry g;
  g.dims = {n, n, n};
  return g;
}

TEST(MarchingCubes, EverySingleCubeCaseIsClosedAndOutward) {
  for (int config = 0; config < 256; ++config) {
    Volume<float> f(cube_geometry(4), -1.0f);
    for (int c = 0; c < 8; ++c) f(1 + (c & 1), 1 + ((c >> 1) & 1), 1 + ((c >> 2) & 1)) = (config >> c) & 1 ? 1.0f : -1.0f;
    const SurfaceMesh m = ctsurg::marching_cubes(f, 0.0);
    ASSERT_EQ(manifold_problem(m), "") << "case " << config;
    EXPECT_TRUE(unique_positions(m)) << "case " << config;
    if (config == 0) {
      EXPECT_EQ(m.triangle_count(), 0);
    } else {
      EXPECT_GT(enclosed_volume(m), 0.0) << "case " << config;
    }
  }
}

// Random fields, outside on the border, on axis-aligned, oblique anisotropic and mirrored lattices.
TEST(MarchingCubes, RandomFieldsAreClosedOrientedManifolds) {
  const Eigen::Matrix3d oblique = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Matrix3d mirrored = Eigen::Vector3d(1, -1, 1).asDiagonal();
  int meshes = 0;
  for (const int64_t n : {3, 5, 8, 13}) {
    for (int seed = 0; seed < 60; ++seed) {
      std::mt19937 rng(static_cast<unsigned>(1000 * n + seed));
      std::uniform_real_distribution<float> u(-1.0f, 1.0f);
      ctsurg::ImageGeometry g = cube_geometry(n);
      g.dims[1] = n + seed % 3;
      if (seed % 3 == 1) {
        g.direction = oblique;
        g.spacing = {0.7, 1.3, 2.1};
        g.origin = {-12.0, 30.0, 5.0};
      } else if (seed % 3 == 2) {
        g.direction = mirrored;
      }
      Volume<float> f(g, -1.0f);
      const bool three_levels = seed % 5 == 0;  // values exactly at iso too
      for (int64_t k = 1; k + 1 < g.dims[2]; ++k)
        for (int64_t j = 1; j + 1 < g.dims[1]; ++j)
          for (int64_t i = 1; i + 1 < g.dims[0]; ++i) f(i, j, k) = three_levels ? std::round(u(rng)) : u(rng) + 0.2f;
      const SurfaceMesh m = ctsurg::marching_cubes(f, 0.0);
      ASSERT_EQ(manifold_problem(m), "") << "n " << n << " seed " << seed;
      if (!three_levels) {
        EXPECT_TRUE(unique_positions(m)) << "n " << n << " seed " << seed;
      }
      if (m.triangle_count() > 0) {
        ++meshes;
        // A field with values exactly at iso can enclose nothing (every vertex on one node).
        if (three_levels) {
          EXPECT_GE(enclosed_volume(m), -1e-9) << "n " << n << " seed " << seed;
        } else {
          EXPECT_GT(enclosed_volume(m), 0.0) << "n " << n << " seed " << seed;
        }
      }
    }
  }
  EXPECT_GT(meshes, 200);
}

ctsurg::PhantomShape shape_of(ctsurg::PhantomKind kind) {
  ctsurg::PhantomShape s;
  s.kind = kind;
  s.centre_mm = {1.3, -2.1, 0.7};
  return s;
}

ctsurg::PhantomRasterOptions raster_options(double spacing) {
  ctsurg::PhantomRasterOptions o;
  o.spacing_mm = Eigen::Vector3d::Constant(spacing);
  o.margin_mm = 2.0 * spacing;
  o.lattice_offset_voxels = {0.21, -0.33, 0.12};
  return o;
}

// The rasterised CT phantom: HU from each voxel's volume fraction (partial volume).
ctsurg::PhantomRaster phantom(ctsurg::PhantomKind kind, double spacing) {
  return ctsurg::rasterise_phantom(shape_of(kind), raster_options(spacing), "test");
}

// The shape's implicit function sampled at the nodes, negated so that inside is >= 0.
Volume<float> implicit_field(ctsurg::PhantomKind kind, double spacing) {
  const auto s = shape_of(kind);
  Volume<float> f(ctsurg::phantom_geometry(s, raster_options(spacing), "test"));
  const auto& g = f.geometry;
  for (int64_t k = 0; k < g.dims[2]; ++k)
    for (int64_t j = 0; j < g.dims[1]; ++j)
      for (int64_t i = 0; i < g.dims[0]; ++i)
        f(i, j, k) = static_cast<float>(-ctsurg::phantom_implicit_mm(s, g.index_to_world(Eigen::Vector3d(double(i), double(j), double(k)))));
  return f;
}

double mid_hu() { return 0.5 * (60.0 + -1000.0); }

// Two fields per phantom: the implicit function sampled at the nodes (smooth, so marching cubes'
// O(h^2) convergence shows) and the rasterised CT (partial-volume HU: a box-filtered indicator, not
// linear across the surface, so linear interpolation along edges leaves an O(h) wobble of
// wavelength h and the area error levels off at a few tenths of a percent while the volume still
// converges).
TEST(MarchingCubes, VolumeAndAreaConvergeOnPhantoms) {
  std::printf("| phantom | field | spacing mm | vertices | triangles | volume rel. error | area rel. error |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  for (const auto kind : {ctsurg::PhantomKind::Sphere, ctsurg::PhantomKind::EllipsoidShell, ctsurg::PhantomKind::Torus}) {
    const auto s = shape_of(kind);
    const double V = ctsurg::phantom_volume_mm3(s), A = ctsurg::phantom_area_mm2(s);
    for (const bool raster : {false, true}) {
      std::vector<double> ev, ea;
      for (const double h : {2.0, 1.0, 0.5}) {
        const SurfaceMesh m = raster ? ctsurg::marching_cubes(phantom(kind, h).hu, mid_hu())
                                     : ctsurg::marching_cubes(implicit_field(kind, h), 0.0);
        ASSERT_EQ(manifold_problem(m), "");
        ev.push_back(enclosed_volume(m) / V - 1.0);
        ea.push_back(area(m) / A - 1.0);
        std::printf("| %s | %s | %.2f | %lld | %lld | %+.5f | %+.5f |\n", ctsurg::phantom_kind_name(kind),
                    raster ? "CT raster, iso -470 HU" : "implicit, iso 0", h, static_cast<long long>(m.vertex_count()),
                    static_cast<long long>(m.triangle_count()), ev.back(), ea.back());
      }
      EXPECT_LT(std::abs(ev[2]), std::abs(ev[0]));
      EXPECT_LT(std::abs(ev[2]), 0.005);
      if (!raster) {
        EXPECT_LT(std::abs(ea[1]), std::abs(ea[0]));
        EXPECT_LT(std::abs(ea[2]), std::abs(ea[1]));
        EXPECT_LT(std::abs(ea[2]), 0.005);
      } else {
        EXPECT_LT(std::abs(ea[2]), 0.01);
      }
    }
  }
}

TEST(MarchingCubes, OutputDoesNotDependOnThreadCount) {
  const auto raster = phantom(ctsurg::PhantomKind::Torus, 0.8);
  const SurfaceMesh a = ctsurg::marching_cubes(raster.hu, mid_hu(), {1});
  for (const int threads : {2, 3}) {
    const SurfaceMesh b = ctsurg::marching_cubes(raster.hu, mid_hu(), {threads});
    EXPECT_EQ(a.vertices, b.vertices);
    EXPECT_EQ(a.normals, b.normals);
    EXPECT_EQ(a.triangles, b.triangles);
    EXPECT_EQ(a.grid_cell, b.grid_cell);
    EXPECT_EQ(a.grid_weights, b.grid_weights);
    EXPECT_EQ(a.nearest_node, b.nearest_node);
  }
}

TEST(MarchingCubes, GridTieReproducesVerticesAndNormalsPointOutward) {
  const auto raster = phantom(ctsurg::PhantomKind::Sphere, 1.0);
  const auto& f = raster.hu;
  const SurfaceMesh m = ctsurg::marching_cubes(f, mid_hu());
  ASSERT_GT(m.vertex_count(), 1000);
  const Eigen::Vector3d centre(1.3, -2.1, 0.7);
  double worst = 0.0;
  for (int64_t v = 0; v < m.vertex_count(); ++v) {
    const std::size_t i = static_cast<std::size_t>(v);
    const Eigen::Vector3i cell(m.grid_cell[3 * i], m.grid_cell[3 * i + 1], m.grid_cell[3 * i + 2]);
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    double sum = 0.0;
    for (int c = 0; c < 8; ++c) {
      const double w = m.grid_weights[8 * i + static_cast<std::size_t>(c)];
      ASSERT_GE(w, 0.0);
      sum += w;
      p += w * f.geometry.index_to_world((cell + Eigen::Vector3i(c & 1, (c >> 1) & 1, (c >> 2) & 1)).cast<double>());
    }
    EXPECT_NEAR(sum, 1.0, 1e-6);
    worst = std::max(worst, (p - vertex(m, static_cast<uint32_t>(v))).norm());
    const Eigen::Vector3i node(m.nearest_node[3 * i], m.nearest_node[3 * i + 1], m.nearest_node[3 * i + 2]);
    ASSERT_GE(f(node[0], node[1], node[2]), mid_hu());
    ASSERT_LE((node.cast<double>() - f.geometry.world_to_index(vertex(m, static_cast<uint32_t>(v)))).norm(), 1.0 + 1e-4);
    const Eigen::Vector3d n(m.normals[3 * i], m.normals[3 * i + 1], m.normals[3 * i + 2]);
    EXPECT_NEAR(n.norm(), 1.0, 1e-5);
    EXPECT_GT(n.dot((vertex(m, static_cast<uint32_t>(v)) - centre).normalized()), 0.95);
  }
  EXPECT_LT(worst, 1e-5);
}

TEST(MarchingCubes, EmptyWhenNothingCrossesAndRejectsBadArguments) {
  Volume<float> f(cube_geometry(5), 0.0f);
  EXPECT_EQ(ctsurg::marching_cubes(f, 0.5).vertex_count(), 0);
  EXPECT_EQ(ctsurg::marching_cubes(f, -0.5).vertex_count(), 0);
  EXPECT_THROW(ctsurg::marching_cubes(f, std::nan("")), ctsurg::InputError);
  ctsurg::ImageGeometry flat = cube_geometry(5);
  flat.dims[2] = 1;
  EXPECT_THROW(ctsurg::marching_cubes(Volume<float>(flat), 0.0), ctsurg::InputError);
  EXPECT_TRUE(ctsurg::inside_touches_border(f, -0.5));
  EXPECT_FALSE(ctsurg::inside_touches_border(f, 0.5));
}

}  // namespace
