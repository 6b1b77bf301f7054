// Trajectories for the animated glTF and HTML viewer tests, on render_test_scenes.h's normal-mapped
// organ: a smooth one (one topology, a bump moving over the front and back to rest, so some morph
// targets are sparse and the last is empty) and the three-frame grab-then-cut one with the slit's
// triangles put back at the end of the cut topology as closing triangles (drawn as the wound), and,
// for a topology that comes back, its frames 0, 2, 0 topologies. Header-only.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "render_test_scenes.h"

namespace ctsurg::test {

// Six frames at 0, 0.1, 0.25, 0.4, 0.5, 0.6 s: a Gaussian bump (sigma 6 mm, up to 5 mm along the
// outward normal) centred on the front (-y), growing then fading; the last frame is the rest again. Far
// from the bump the vertices do not move at all (the Gaussian underflows to below a float's resolution).
inline Trajectory bump_trajectory(const SurfaceMesh& surface) {
  Trajectory t;
  t.scenario = "gltf test";
  t.model = "synthetic";
  t.surface_file = "synthetic";
  t.dt_s = 1e-3;
  t.time = {0.0, 0.1, 0.25, 0.4, 0.5, 0.6};
  const double height[] = {0.0, 2.0, 5.0, 3.0, 1.0, 0.0};  // mm
  t.rest_vertices = surface.vertices;
  const std::size_t nv = surface.vertices.size() / 3;
  const double centre[3] = {0.0, -kSceneRadii[1], 0.0};
  for (std::size_t f = 0; f < t.time.size(); ++f)
    for (std::size_t i = 0; i < nv; ++i) {
      const float* p = &surface.vertices[3 * i];
      const float* n = &surface.normals[3 * i];
      double d2 = 0.0;
      for (int k = 0; k < 3; ++k) d2 += (p[k] - centre[k]) * (p[k] - centre[k]);
      const double w = height[f] * std::exp(-d2 / (2.0 * 6.0 * 6.0));
      for (int k = 0; k < 3; ++k) t.vertices.push_back(static_cast<float>(p[k] + w * n[k]));
    }
  t.topologies.push_back(surface.triangles);
  t.topology_of_frame.assign(t.time.size(), 0);
  return t;
}

// three_frame_trajectory() (rest, grabbed, cut at 0, 0.5, 1 s) with the slit's triangles appended to
// the cut topology as its closing triangles.
inline Trajectory cut_trajectory_with_wound(const SurfaceMesh& surface) {
  Trajectory t = three_frame_trajectory(surface);
  const std::vector<uint32_t>& all = t.topologies[0];
  std::vector<uint32_t>& cut = t.topologies[1];
  const std::size_t kept = cut.size() / 3;
  // The removed triangles: those of topology 0 not in topology 1 (same order, so a merge walk).
  std::size_t c = 0;
  std::vector<uint32_t> removed;
  for (std::size_t f = 0; f < all.size(); f += 3) {
    if (c < cut.size() && all[f] == cut[c] && all[f + 1] == cut[c + 1] && all[f + 2] == cut[c + 2]) {
      c += 3;
    } else {
      removed.insert(removed.end(), all.begin() + long(f), all.begin() + long(f) + 3);
    }
  }
  cut.insert(cut.end(), removed.begin(), removed.end());
  t.closing_triangles = {0, static_cast<int64_t>(cut.size() / 3 - kept)};
  return t;
}

}  // namespace ctsurg::test
