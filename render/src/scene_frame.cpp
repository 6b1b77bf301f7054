#include "ctsurg/render/scene_frame.h"

#include <Eigen/Geometry>

#include <cmath>

#include "ctsurg/core/error.h"

namespace ctsurg {

SceneFrame rest_scene_frame(const SurfaceMesh& surface) {
  SceneFrame f;
  f.vertices = surface.vertices.data();
  f.triangles = &surface.triangles;
  f.topology = -1;
  return f;
}

SceneFrame trajectory_scene_frame(const Trajectory& trajectory, int64_t f) {
  SceneFrame s;
  s.vertices = trajectory.frame_vertices(f);
  s.triangles = &trajectory.frame_triangles(f);
  s.topology = trajectory.topology_of_frame[static_cast<std::size_t>(f)];
  s.region = trajectory.frame_region(f);
  if (!trajectory.closing_triangles.empty()) s.closing_triangles = trajectory.closing_triangles[static_cast<std::size_t>(s.topology)];
  const int64_t n_spheres = trajectory.sphere_count();
  for (int64_t i = 0; i < n_spheres && !trajectory.spheres.empty(); ++i) {
    const double* q = trajectory.spheres.data() + 4 * (f * n_spheres + i);
    if (!(q[3] > 0.0)) continue;
    ToolSphere t{{float(q[0]), float(q[1]), float(q[2])}, float(q[3]),
                 trajectory.sphere_kinds[static_cast<std::size_t>(i)] == "grab"};
    s.spheres.push_back(t);
  }
  const int64_t n_blades = trajectory.blade_count();
  for (int64_t i = 0; i < n_blades; ++i) {
    const double* q = trajectory.blades.data() + 7 * (f * n_blades + i);
    if (q[6] == 0.0) continue;
    s.blades.push_back({{float(q[0]), float(q[1]), float(q[2])}, {float(q[3]), float(q[4]), float(q[5])}});
  }
  const int64_t n_stitches = trajectory.stitch_count();
  for (int64_t i = 0; i < n_stitches; ++i) {
    const double* q = trajectory.stitches.data() + 7 * (f * n_stitches + i);
    if (q[6] == 0.0) continue;
    const Eigen::Vector3d a(q[0], q[1], q[2]), b(q[3], q[4], q[5]);
    if (!((b - a).norm() > 1e-6)) continue;
    const Eigen::Vector3d axis = (b - a).normalized(), u = axis.unitOrthogonal(), v = axis.cross(u);
    constexpr int kSides = 8;
    for (int k = 0; k < kSides; ++k) {
      const double p0 = 2 * M_PI * k / kSides, p1 = 2 * M_PI * (k + 1) / kSides, pm = 0.5 * (p0 + p1);
      const Eigen::Vector3d r0 = kStitchRadiusMm * (std::cos(p0) * u + std::sin(p0) * v);
      const Eigen::Vector3d r1 = kStitchRadiusMm * (std::cos(p1) * u + std::sin(p1) * v);
      const Eigen::Vector3d n = std::cos(pm) * u + std::sin(pm) * v;
      for (const Eigen::Vector3d& c : {Eigen::Vector3d(a + r0), Eigen::Vector3d(b + r0), Eigen::Vector3d(b + r1),
                                       Eigen::Vector3d(a + r0), Eigen::Vector3d(b + r1), Eigen::Vector3d(a + r1)}) {
        s.stitch_triangles.insert(s.stitch_triangles.end(), {float(c.x()), float(c.y()), float(c.z()), float(n.x()), float(n.y()), float(n.z())});
      }
    }
  }
  const size_t n_instruments = trajectory.instruments.size();
  for (size_t k = 0; k < n_instruments; ++k) {
    const double* pose = trajectory.instrument_poses.data() + 8 * (static_cast<size_t>(f) * n_instruments + k);
    if (pose[0] == 0.0) continue;
    const Eigen::Quaterniond q(pose[1], pose[2], pose[3], pose[4]);
    const Eigen::Matrix3d r = q.normalized().toRotationMatrix();
    const Eigen::Vector3d c(pose[5], pose[6], pose[7]);
    const TrajectoryInstrument& ins = trajectory.instruments[k];
    const auto corner = [&](uint32_t v) {
      return Eigen::Vector3d(r * Eigen::Vector3d(ins.vertices[3 * v], ins.vertices[3 * v + 1], ins.vertices[3 * v + 2]) + c);
    };
    for (size_t t = 0; t < ins.triangles.size(); t += 3) {
      const Eigen::Vector3d a = corner(ins.triangles[t]), b = corner(ins.triangles[t + 1]), d = corner(ins.triangles[t + 2]);
      Eigen::Vector3d n = (b - a).cross(d - a);
      n = n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d::UnitZ();
      for (const Eigen::Vector3d* p : {&a, &b, &d}) {
        s.instrument_triangles.insert(s.instrument_triangles.end(), {float(p->x()), float(p->y()), float(p->z()), float(n.x()),
                                                                      float(n.y()), float(n.z())});
      }
    }
  }
  return s;
}

void check_trajectory_matches_surface(const Trajectory& trajectory, const std::string& trajectory_file,
                                      const SurfaceMesh& surface, const std::string& surface_file) {
  if (trajectory.vertex_count() != surface.vertex_count()) {
    throw InputError(trajectory_file, "/trajectory/surface/rest_vertices",
                     std::to_string(trajectory.vertex_count()) + " vertices, but the surface " + surface_file + " has " +
                         std::to_string(surface.vertex_count()) +
                         " (/surface/vertices): the trajectory was simulated with another surface");
  }
  if (trajectory.frame_count() < 1) throw InputError(trajectory_file, "/trajectory/time", "no frames");
}

std::vector<float> vertex_distances(const float* a, const float* b, int64_t vertex_count) {
  std::vector<float> d(static_cast<std::size_t>(vertex_count));
  for (int64_t v = 0; v < vertex_count; ++v) {
    const double dx = double(a[3 * v]) - b[3 * v], dy = double(a[3 * v + 1]) - b[3 * v + 1], dz = double(a[3 * v + 2]) - b[3 * v + 2];
    d[static_cast<std::size_t>(v)] = static_cast<float>(std::sqrt(dx * dx + dy * dy + dz * dz));
  }
  return d;
}

BoundingSphere scene_bounds(const SurfaceMesh& surface, const Trajectory* trajectory, const std::vector<int64_t>& frames) {
  BoundingSphere s = bounding_sphere(surface.vertices.data(), surface.vertex_count());
  if (trajectory)
    for (const int64_t f : frames) s = bounding_sphere(trajectory->frame_vertices(f), trajectory->vertex_count(), s);
  return s;
}

}  // namespace ctsurg
