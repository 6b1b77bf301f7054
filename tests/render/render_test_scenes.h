// Synthetic scenes for the render tests: a normal-mapped "organ" (an ellipsoid with an exact UV
// parametrisation, glTF tangents and a procedural bump map, so the detail lives in the map only) and a
// three-frame trajectory on it: rest, grabbed (pulled towards the viewer by a grab sphere), cut (a slit
// with the blade, the inside showing). Header-only; shared by the render test programs.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "ctsurg/core/surface_mesh_file.h"
#include "ctsurg/core/trajectory_file.h"

namespace ctsurg::test {

inline constexpr double kSceneRadii[3] = {22.0, 18.0, 28.0};  // mm, x y z

// Ellipsoid over (u, v) in [0, 1]^2: u around +z (from +x towards +y), v from the top (+z) down.
inline SurfaceMesh bumpy_organ_surface(int segments = 48, int rings = 24, int map_width = 256) {
  constexpr double kPi = 3.14159265358979323846;
  const double a = kSceneRadii[0], b = kSceneRadii[1], c = kSceneRadii[2];
  SurfaceMesh m;
  const int cols = segments + 1;  // the u = 1 column copies u = 0 (an atlas seam)
  for (int r = 0; r <= rings; ++r)
    for (int s = 0; s < cols; ++s) {
      const double u = double(s) / segments, v = double(r) / rings;
      const double phi = 2.0 * kPi * u, theta = kPi * v;
      const double x = a * std::sin(theta) * std::cos(phi), y = b * std::sin(theta) * std::sin(phi), z = c * std::cos(theta);
      m.vertices.insert(m.vertices.end(), {float(x), float(y), float(z)});
      double n[3] = {x / (a * a), y / (b * b), z / (c * c)};
      const double nn = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      for (double& q : n) q /= nn;
      m.normals.insert(m.normals.end(), {float(n[0]), float(n[1]), float(n[2])});
      // Tangent along +u (around +z), orthogonal to the normal; at the poles any horizontal direction.
      double t[3] = {-std::sin(phi), std::cos(phi), 0.0};
      const double d = t[0] * n[0] + t[1] * n[1] + t[2] * n[2];
      for (int k = 0; k < 3; ++k) t[k] -= d * n[k];
      const double tn = std::sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
      // w = +1: cross(n, t) points up (towards +z, decreasing v), as glTF wants.
      m.tangents.insert(m.tangents.end(), {float(t[0] / tn), float(t[1] / tn), float(t[2] / tn), 1.0f});
      m.uvs.insert(m.uvs.end(), {float(u), float(v)});
      const uint32_t source = static_cast<uint32_t>(r == 0 ? 0 : r == rings ? 1 + (rings - 1) * segments : 1 + (r - 1) * segments + s % segments);
      m.source_vertex.push_back(source);
    }
  m.source_vertex_count = 2 + (rings - 1) * segments;
  for (int r = 0; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const uint32_t i00 = uint32_t(r * cols + s), i01 = i00 + 1, i10 = i00 + uint32_t(cols), i11 = i10 + 1;
      // Counter-clockwise seen from outside (u increases eastwards, v southwards).
      if (r != 0) m.triangles.insert(m.triangles.end(), {i00, i10, i01});
      if (r != rings - 1) m.triangles.insert(m.triangles.end(), {i01, i10, i11});
    }
  const std::size_t nv = m.vertices.size() / 3;
  m.grid_cell.assign(3 * nv, 0);
  m.grid_weights.assign(8 * nv, 0.0f);
  for (std::size_t i = 0; i < nv; ++i) m.grid_weights[8 * i] = 1.0f;
  m.nearest_node.assign(3 * nv, 0);
  m.lattice.dims = {2, 2, 2};
  m.lattice.spacing = Eigen::Vector3d::Constant(1.0);
  m.iso = 0.5;
  m.quantity = "fraction";
  m.source_dataset = "/grid/fraction";
  // Bumps: height h = sin(2 pi 16 u) sin(2 pi 8 v); tangent-space normal from its slope (strong, so
  // that a renderer ignoring the map draws a visibly smooth ellipsoid).
  NormalMapImage& map = m.normal_map;
  map.width = map_width;
  map.height = map_width / 2;
  map.bits = 8;
  map.rgb.resize(3 * static_cast<std::size_t>(map.width * map.height));
  for (int64_t y = 0; y < map.height; ++y)
    for (int64_t x = 0; x < map.width; ++x) {
      const double u = (x + 0.5) / double(map.width), v = (y + 0.5) / double(map.height);
      const double k = 0.9;
      const double dhdu = k * std::cos(2 * kPi * 16 * u) * std::sin(2 * kPi * 8 * v);
      const double dhdv = k * std::sin(2 * kPi * 16 * u) * std::cos(2 * kPi * 8 * v);
      // x along +u, y along -v (the bitangent points up the image).
      double n[3] = {-dhdu, dhdv, 1.0};
      const double nn = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      for (int q = 0; q < 3; ++q)
        map.rgb[3 * static_cast<std::size_t>(y * map.width + x) + q] =
            static_cast<uint16_t>(std::lround((n[q] / nn + 1.0) * 0.5 * 255.0));
    }
  return m;
}

// Three frames on `surface`: 0 rest; 1 grabbed: the front (-y) pulled 9 mm towards the viewer and up,
// a grab sphere at the grabbed point; 2 cut: a vertical slit on the front (triangles removed, topology
// 1), its lips pushed apart, the blade in the slit.
inline Trajectory three_frame_trajectory(const SurfaceMesh& surface) {
  Trajectory t;
  t.scenario = "render test";
  t.model = "synthetic";
  t.surface_file = "synthetic";
  t.dt_s = 1e-3;
  t.time = {0.0, 0.5, 1.0};
  t.rest_vertices = surface.vertices;
  const std::size_t nv = surface.vertices.size() / 3;
  t.vertices.resize(3 * 3 * nv);
  const double grab_at[3] = {0.0, -kSceneRadii[1], 4.0};
  const double pull[3] = {0.0, -9.0, 3.0};
  for (std::size_t i = 0; i < nv; ++i) {
    const float* p = surface.vertices.data() + 3 * i;
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) d2 += (p[k] - grab_at[k]) * (p[k] - grab_at[k]);
    const double w = std::exp(-d2 / (2.0 * 9.0 * 9.0));
    // Cut opening: points in front, near x = 0 and within the slit's height, pushed apart in x.
    const double opening = p[1] < 0.0 ? 2.5 * std::exp(-p[0] * p[0] / (2.0 * 4.0 * 4.0)) * (std::abs(p[2]) < 14.0 ? 1.0 : 0.0) : 0.0;
    for (int k = 0; k < 3; ++k) {
      t.vertices[0 * 3 * nv + 3 * i + k] = p[k];
      t.vertices[1 * 3 * nv + 3 * i + k] = static_cast<float>(p[k] + w * pull[k]);
      t.vertices[2 * 3 * nv + 3 * i + k] = p[k] + (k == 0 ? static_cast<float>(p[0] >= 0.0f ? opening : -opening) : 0.0f);
    }
  }
  t.topologies.push_back(surface.triangles);
  std::vector<uint32_t> cut;
  for (std::size_t f = 0; f < surface.triangles.size(); f += 3) {
    double centroid[3] = {0, 0, 0};
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) centroid[k] += surface.vertices[3 * surface.triangles[f + c] + k] / 3.0;
    const bool in_slit = std::abs(centroid[0]) < 3.0 && centroid[1] < 0.0 && std::abs(centroid[2]) < 14.0;
    if (!in_slit) cut.insert(cut.end(), surface.triangles.begin() + long(f), surface.triangles.begin() + long(f) + 3);
  }
  t.topologies.push_back(cut);
  t.topology_of_frame = {0, 0, 1};
  t.sphere_kinds = {"grab"};
  t.spheres = {0, 0, 0, 0,  //
               grab_at[0] + pull[0], grab_at[1] + pull[1], grab_at[2] + pull[2], 4.0,  //
               0, 0, 0, 0};
  t.blades = {0, 0, 0, 0, 0, 0, 0,  //
              0, 0, 0, 0, 0, 0, 0,  //
              0.0, -kSceneRadii[1] - 6.0, 14.0, 0.0, -kSceneRadii[1] + 4.0, -12.0, 1.0};
  TrajectoryMetric m{"max_displacement", "mm", {0.0, 9.5, 2.5}};
  t.metrics.push_back(m);
  return t;
}

}  // namespace ctsurg::test
