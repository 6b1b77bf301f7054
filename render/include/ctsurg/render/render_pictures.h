// What one ctsurg-render call draws: frames of a surface or a trajectory from one view, a turntable,
// or comparisons against a reference (the rest surface, or another model's trajectory or surface):
// side by side, overlay, or a heat map of the per-vertex distance with a colour bar in mm.
//
// Every picture of a call shares one camera (framed on the rest surface, every requested frame and the
// reference together), so a sequence does not jump and compared pictures line up pixel for pixel.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "ctsurg/core/surface_mesh_file.h"
#include "ctsurg/core/trajectory_file.h"
#include "ctsurg/render/camera.h"
#include "ctsurg/render/rgb_image.h"
#include "ctsurg/render/surface_renderer.h"

namespace ctsurg {

enum class Layout { single, side_by_side, overlay, heat_map };

// One model: a surface file and, optionally, a trajectory simulated on it (checked to match).
struct RenderModel {
  const SurfaceMesh* surface = nullptr;
  std::string surface_name;              // for messages and captions
  const Trajectory* trajectory = nullptr;  // or nullptr: the rest surface only
  std::string trajectory_name;
};

struct PictureRequest {
  int width = 512, height = 512;  // pixels of each rendered view (a comparison is wider)
  int samples = 4;                // multisampling: 1 (none) or 4
  Projection projection = Projection::perspective;
  ViewDirection view;             // parse_view("anterior") by default in the tool
  std::vector<int64_t> frames;    // trajectory frames to draw; empty: the rest surface
  int turntable_steps = 0;        // > 0: this many views around +z (from `view`), of the first frame
  Layout layout = Layout::single;
  bool reference_is_rest = true;  // compare against the model's rest surface, or `reference` below
  RenderModel reference;          // another model (its frame f is compared with frame f)
  double heat_max_mm = 0.0;       // top of the colour bar; 0: the largest value over all pictures
  bool captions = true;           // frame / model captions on comparisons and sequences
  RenderStyle style;
};

struct Picture {
  std::string tag;  // "rest", "0012" (frame), "turn007" (turntable step): names the output file
  RgbImage image;
};

// Checks `request` against `model` (frames in range, trajectory matching its surface, reference
// matching for heat maps): InputError naming the file or option. Then renders each picture in turn
// and hands it to `emit` (so long sequences are not held in memory).
void render_pictures(const RenderModel& model, const PictureRequest& request, const std::function<void(Picture&&)>& emit);

// Parses "rest", "last", "all", "N", "A:B" (inclusive) or "A:B:STEP" and comma lists of those into
// frame indices (ascending, unique) of a trajectory with `frame_count` frames; "rest" gives none.
// InputError(option, ...) on a bad or out-of-range spec.
std::vector<int64_t> parse_frames(const std::string& spec, int64_t frame_count, const std::string& option = "--frames");

}  // namespace ctsurg
