#include "ctsurg/mesh/surface_decimation.h"

#include "ctsurg/core/error.h"
#include "ctsurg/mesh/surface_smoothing.h"

// GCC 12 reports a false -Wmaybe-uninitialized in Eigen's 4x4 copy inside CGAL's quadric policies.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Bounded_normal_change_filter.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Count_stop_predicate.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/GarlandHeckbert_plane_policies.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>

#include <array>
#include <string>
#include <vector>

namespace ctsurg {

namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;
namespace SMS = CGAL::Surface_mesh_simplification;
namespace PMP = CGAL::Polygon_mesh_processing;
}  // namespace

void decimate_surface(SurfaceMesh& mesh, int64_t target_triangles) {
  if (target_triangles < 4) {
    throw InputError("--decimate", "target", "the target triangle count must be at least 4, got " + std::to_string(target_triangles));
  }
  if (target_triangles >= mesh.triangle_count()) return;

  std::vector<Point> points;
  points.reserve(static_cast<std::size_t>(mesh.vertex_count()));
  for (std::size_t v = 0; v < mesh.vertices.size(); v += 3) {
    points.emplace_back(mesh.vertices[v], mesh.vertices[v + 1], mesh.vertices[v + 2]);
  }
  std::vector<std::array<std::size_t, 3>> faces;
  faces.reserve(static_cast<std::size_t>(mesh.triangle_count()));
  for (std::size_t t = 0; t < mesh.triangles.size(); t += 3) {
    faces.push_back({mesh.triangles[t], mesh.triangles[t + 1], mesh.triangles[t + 2]});
  }
  // Marching cubes can make two sheets meet at one vertex (a non-manifold vertex); the soup
  // orientation duplicates such vertices so that the halfedge structure can hold the mesh. The
  // orientation itself is already consistent and is kept.
  PMP::orient_polygon_soup(points, faces);
  Mesh sm;
  PMP::polygon_soup_to_polygon_mesh(points, faces, sm);
  if (sm.number_of_faces() != faces.size()) {
    throw RuntimeError("surface decimation: the surface could not be built as a polygon mesh");
  }

  SMS::Count_stop_predicate<Mesh> stop(static_cast<std::size_t>(3 * target_triangles / 2));
  SMS::GarlandHeckbert_plane_policies<Mesh, Kernel> quadrics(sm);
  SMS::Bounded_normal_change_filter<> no_flips;
  SMS::edge_collapse(sm, stop,
                     CGAL::parameters::get_cost(quadrics.get_cost()).get_placement(quadrics.get_placement()).filter(no_flips));
  sm.collect_garbage();

  mesh.vertices.clear();
  mesh.vertices.reserve(3 * sm.number_of_vertices());
  for (const auto v : sm.vertices()) {
    const Point& p = sm.point(v);
    for (int a = 0; a < 3; ++a) mesh.vertices.push_back(static_cast<float>(p[a]));
  }
  mesh.triangles.clear();
  mesh.triangles.reserve(3 * sm.number_of_faces());
  for (const auto f : sm.faces()) {
    for (const auto v : CGAL::vertices_around_face(sm.halfedge(f), sm)) mesh.triangles.push_back(static_cast<uint32_t>(v.idx()));
  }
  mesh.normals.clear();
  recompute_vertex_normals(mesh);
  mesh.grid_cell.clear();
  mesh.grid_weights.clear();
  mesh.nearest_node.clear();
}

}  // namespace ctsurg
