// Tests for ctsurg/render/trajectory_surface.h: a trajectory simulated without a surface file is drawn
// by its own triangles (a tetrahedron's boundary here): the rest vertices and first topology, outward
// unit normals (a vertex no triangle uses gets a unit normal too); a trajectory that names its surface
// file, or has no triangles, is refused naming the field.
#include "ctsurg/render/trajectory_surface.h"

#include "ctsurg/core/error.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ctsurg {
namespace {

Trajectory tetrahedron() {
  Trajectory t;
  // Corners of a positively oriented tet, and an interior point no triangle uses.
  t.rest_vertices = {0, 0, 0, 2, 0, 0, 0, 2, 0, 0, 0, 2, 0.4f, 0.4f, 0.4f};
  t.topologies = {{0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2}};  // wound outwards
  return t;
}

TEST(TrajectorySurface, TheBoundaryWithOutwardUnitNormals) {
  const SurfaceMesh m = trajectory_surface(tetrahedron(), "t.h5");
  EXPECT_EQ(m.vertices, tetrahedron().rest_vertices);
  EXPECT_EQ(m.triangles, tetrahedron().topologies[0]);
  ASSERT_EQ(m.normals.size(), m.vertices.size());
  const float centroid[3] = {0.5f, 0.5f, 0.5f};
  for (int v = 0; v < 4; ++v) {
    double len = 0, out = 0;
    for (int a = 0; a < 3; ++a) {
      len += m.normals[3 * v + a] * m.normals[3 * v + a];
      out += m.normals[3 * v + a] * (m.vertices[3 * v + a] - centroid[a]);
    }
    EXPECT_NEAR(len, 1, 1e-6) << v;
    EXPECT_GT(out, 0) << v;  // outward
  }
  EXPECT_NEAR(m.normals[14], 1, 1e-6);  // the unused interior vertex
}

TEST(TrajectorySurface, ASurfaceFileOrNoTrianglesIsRefused) {
  Trajectory named = tetrahedron();
  named.surface_file = "surface_textured.h5";
  try {
    trajectory_surface(named, "t.h5");
    FAIL() << "a trajectory simulated on a surface file was drawn without it";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("surface_textured.h5"), std::string::npos) << e.what();
  }
  Trajectory points = tetrahedron();
  points.topologies = {{}};
  EXPECT_THROW(trajectory_surface(points, "t.h5"), InputError);
  Trajectory bad = tetrahedron();
  bad.topologies[0][4] = 7;  // past the five vertices
  EXPECT_THROW(trajectory_surface(bad, "t.h5"), InputError);
}

}  // namespace
}  // namespace ctsurg
