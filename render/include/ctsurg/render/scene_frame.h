// One picture's content: the surface's vertex positions and triangles at an instant, the tools, and
// optionally a value per vertex for a heat map; built from a rest surface or a trajectory frame.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "ctsurg/core/surface_mesh_file.h"
#include "ctsurg/core/trajectory_file.h"
#include "ctsurg/render/camera.h"

namespace ctsurg {

struct ToolSphere {
  float centre[3];  // LPS mm
  float radius;     // mm (> 0)
  bool grab;        // grab (drawn green) or probe (drawn blue)
};
struct ToolBlade {
  float a[3], b[3];  // the cutting edge's ends, LPS mm
};

// A stitch is drawn as an 8-sided cylinder of this radius (mm): a 3-0 suture is 0.2-0.25 mm across,
// drawn thicker to be seen at an organ's scale.
inline constexpr float kStitchRadiusMm = 0.35f;

struct SceneFrame {
  const float* vertices = nullptr;                // #V x 3, LPS mm (not owned)
  const std::vector<uint32_t>* triangles = nullptr;  // #T x 3 (not owned)
  int topology = 0;                               // id of `triangles` (cache key for frames)
  int64_t closing_triangles = 0;                  // the last ones of `triangles` close cut holes: drawn as
                                                  //   the wound's inside
  std::vector<ToolSphere> spheres;                // active spheres only
  std::vector<ToolBlade> blades;                  // active blades only
  std::vector<float> instrument_triangles;        // active instruments at their poses: #T x 3 corners x
                                                  //   (position LPS mm, unit face normal), flat shaded
  std::vector<float> stitch_triangles;            // placed stitches as thin cylinders (kStitchRadiusMm), the
                                                  //   same layout as instrument_triangles
  std::vector<float> values;                      // #V heat-map values (mm) or empty
  const uint8_t* region = nullptr;                // #V FEM local-region flags (0 outside, 1 region, 2 its
                                                  //   interface; not owned) or nullptr: none
};

// The rest surface (topology id -1).
SceneFrame rest_scene_frame(const SurfaceMesh& surface);
// Frame f of a trajectory (tools and its local region included; topology id = the trajectory's topology
// index).
SceneFrame trajectory_scene_frame(const Trajectory& trajectory, int64_t f);

// InputError naming both files and /trajectory/surface/rest_vertices when the trajectory's vertex
// count differs from the surface's (the trajectory was made with another surface).
void check_trajectory_matches_surface(const Trajectory& trajectory, const std::string& trajectory_file,
                                      const SurfaceMesh& surface, const std::string& surface_file);

// Per-vertex distance |a_v - b_v| (mm) between two #V x 3 position arrays.
std::vector<float> vertex_distances(const float* a, const float* b, int64_t vertex_count);

// The sphere holding the rest surface and every listed trajectory frame (frames may be empty).
BoundingSphere scene_bounds(const SurfaceMesh& surface, const Trajectory* trajectory, const std::vector<int64_t>& frames);

}  // namespace ctsurg
