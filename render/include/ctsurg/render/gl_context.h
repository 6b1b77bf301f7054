// An offscreen OpenGL 4.5 core context through OSMesa (Mesa's llvmpipe rasteriser: no GPU, no window
// system, no X), rendering into a framebuffer object of a fixed size with optional multisampling,
// read back as an RgbImage.
//
// Determinism: llvmpipe rasterises and shades the same input to the same pixels whatever its thread
// count (LP_NUM_THREADS changes how the tiles are shared, not what each tile computes); the context
// fixes everything else (no dithering, fixed sample count).
#pragma once

#include <memory>

#include "ctsurg/render/rgb_image.h"

namespace ctsurg {

class OffscreenGlContext {
 public:
  // width x height pixels (each 1 .. the implementation's limit, 16384 on llvmpipe), `samples` 1 (none)
  // or up to GL_MAX_SAMPLES (4 on llvmpipe). InputError("OpenGL", ...) when the sizes are out of range
  // or no OpenGL 4.5 core context can be created (OSMesa missing or too old): exit 2 in the tools.
  OffscreenGlContext(int width, int height, int samples);
  ~OffscreenGlContext();
  OffscreenGlContext(const OffscreenGlContext&) = delete;
  OffscreenGlContext& operator=(const OffscreenGlContext&) = delete;

  // Makes this context current and binds its (multisampled) framebuffer as the draw target.
  void make_current();
  // Resolves the samples and reads the picture (row 0 at the top). The context must be current.
  RgbImage read_pixels();
  // Waits for the rasteriser to finish everything queued (for timing).
  void finish();

  int width() const;
  int height() const;
  int samples() const;
  // "4.5 (Core Profile) Mesa 22.3.6, llvmpipe (LLVM 15.0.6, 256 bits)"
  std::string description() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace ctsurg
