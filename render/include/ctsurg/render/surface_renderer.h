// The surface renderer: OpenGL 4.5 core shaders over an OSMesa context (gl_context.h).
//
// The rest geometry is uploaded once: texture coordinates as a vertex attribute, the normal map as a
// mipmapped texture, each topology's triangles as an index buffer (kept per topology id). Each frame
// streams only what moves: positions, normals and tangents into buffer textures that the vertex shader
// reads by gl_VertexID (vertex texture fetch, as the GPU spring-mass papers stream particle positions),
// plus heat-map values when asked.
//
// Shading, per pixel: the tangent-space normal map applied in the deformed tangent frame
// (deformed_tangent_frames.h), Blinn-Phong with a key light above-left of the camera, a fill light and
// a little ambient. Two-sided: back faces (the inside, seen through a cut) get the flipped normal and
// a darker red, so incisions read clearly; so do the triangles closing a cut's holes (SceneFrame::
// closing_triangles), front or back, so a closed incision still reads as a wound. Heat maps colour the surface through the Turbo table
// (colour_map.h) at value / heat_max_mm, keeping the lighting. The FEM local region (SceneFrame::region),
// when drawn: its vertices hatched in RenderStyle::region_rgb (diagonal stripes in screen space, so the
// colour or heat value underneath still shows between them), its interface as a dark band. Tools: spheres as translucent
// icospheres (grab green, probe blue), blades as translucent steel quads on the cutting edge, suture
// stitches as opaque violet cylinders.
#pragma once

#include <memory>

#include "ctsurg/core/surface_mesh_file.h"
#include "ctsurg/render/camera.h"
#include "ctsurg/render/gl_context.h"
#include "ctsurg/render/rgb_image.h"
#include "ctsurg/render/scene_frame.h"

namespace ctsurg {

struct RenderStyle {
  bool normal_map = true;        // use the surface's normal map when it has one
  bool tools = true;             // draw the frame's spheres and blades
  bool heat_map = false;         // colour by SceneFrame::values
  float heat_max_mm = 1.0f;      // the value at the top of the colour map (> 0)
  float tissue_rgb[3] = {0.78f, 0.38f, 0.34f};  // linear-ish albedo of the outside
  float background_rgb[3] = {0.11f, 0.12f, 0.14f};
  bool region = true;            // hatch the frame's local region when it has one (SceneFrame::region)
  float region_rgb[3] = {0.1f, 0.85f, 0.9f};  // the region's stripes (a cyan far from the tissue's red)
};

class SurfaceRenderer {
 public:
  // Owns an OffscreenGlContext of width x height x samples (see its errors) and uploads `surface`.
  SurfaceRenderer(const SurfaceMesh& surface, int width, int height, int samples);
  ~SurfaceRenderer();
  SurfaceRenderer(const SurfaceRenderer&) = delete;
  SurfaceRenderer& operator=(const SurfaceRenderer&) = delete;

  // Draws `frame` (its #V must be the surface's) and reads the picture back.
  RgbImage render(const SceneFrame& frame, const Camera& camera, const RenderStyle& style);
  // Draws without reading back (benchmarks: call finish() to wait for the pixels).
  void draw(const SceneFrame& frame, const Camera& camera, const RenderStyle& style);
  void finish();

  bool has_normal_map() const;
  OffscreenGlContext& context();

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace ctsurg
