#include "ctsurg/render/trajectory_surface.h"

#include "ctsurg/core/error.h"

#include <cmath>

namespace ctsurg {

SurfaceMesh trajectory_surface(const Trajectory& trajectory, const std::string& trajectory_name) {
  if (!trajectory.surface_file.empty()) {
    throw InputError(trajectory_name, "/trajectory@surface_file",
                     "simulated on the surface '" + trajectory.surface_file + "': give it with --surface");
  }
  if (trajectory.topologies.empty() || trajectory.topologies.front().empty()) {
    throw InputError(trajectory_name, "/trajectory/surface/triangles",
                     "no triangles: the trajectory is a point set (simulated without a surface on a model that has none)");
  }
  SurfaceMesh mesh;
  mesh.vertices = trajectory.rest_vertices;
  mesh.triangles = trajectory.topologies.front();
  const size_t nv = mesh.vertices.size() / 3;
  std::vector<double> n(3 * nv, 0.0);
  for (size_t t = 0; t < mesh.triangles.size(); t += 3) {
    const uint32_t a = mesh.triangles[t], b = mesh.triangles[t + 1], c = mesh.triangles[t + 2];
    if (a >= nv || b >= nv || c >= nv) {
      throw InputError(trajectory_name, "/trajectory/surface/triangles", "triangle " + std::to_string(t / 3) + " names a vertex past the " +
                                                                          std::to_string(nv) + " rest vertices");
    }
    const float* p = &mesh.vertices[3 * a];
    const float* q = &mesh.vertices[3 * b];
    const float* r = &mesh.vertices[3 * c];
    const double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]}, v[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
    const double f[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};  // 2 x area
    for (const uint32_t k : {a, b, c})
      for (size_t d = 0; d < 3; ++d) n[3 * k + d] += f[d];
  }
  mesh.normals.resize(3 * nv);
  for (size_t k = 0; k < nv; ++k) {
    const double len = std::sqrt(n[3 * k] * n[3 * k] + n[3 * k + 1] * n[3 * k + 1] + n[3 * k + 2] * n[3 * k + 2]);
    // A vertex no triangle uses (an interior node) is never drawn; it gets a unit normal all the same.
    for (size_t d = 0; d < 3; ++d) mesh.normals[3 * k + d] = len > 0 ? static_cast<float>(n[3 * k + d] / len) : (d == 2 ? 1.0f : 0.0f);
  }
  return mesh;
}

}  // namespace ctsurg
