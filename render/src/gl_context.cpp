// OSMesa is confined to this file and surface_renderer.cpp.
#define GL_GLEXT_PROTOTYPES 1
#include "ctsurg/render/gl_context.h"

#include <GL/osmesa.h>
#include <GL/glcorearb.h>

#include <string>
#include <vector>

#include "ctsurg/core/error.h"

namespace ctsurg {

struct OffscreenGlContext::State {
  OSMesaContext context = nullptr;
  std::vector<unsigned char> default_buffer;  // OSMesa needs one; pictures go to the framebuffer objects
  int width = 0, height = 0, samples = 1;
  GLuint fbo = 0, colour = 0, depth = 0;     // drawn into (multisampled when samples > 1)
  GLuint resolve_fbo = 0, resolve_colour = 0;
};

namespace {
constexpr int kDefaultBufferSide = 16;
}

OffscreenGlContext::OffscreenGlContext(int width, int height, int samples) : state_(std::make_unique<State>()) {
  if (width < 1 || height < 1) {
    throw InputError("OpenGL", "image size",
                     "must be at least 1 x 1 pixels, got " + std::to_string(width) + " x " + std::to_string(height));
  }
  if (samples < 1) throw InputError("OpenGL", "samples", "must be at least 1, got " + std::to_string(samples));
  const int attribs[] = {OSMESA_FORMAT,         OSMESA_RGBA,          OSMESA_DEPTH_BITS,
                         24,                    OSMESA_PROFILE,       OSMESA_CORE_PROFILE,
                         OSMESA_CONTEXT_MAJOR_VERSION, 4, OSMESA_CONTEXT_MINOR_VERSION, 5, 0};
  State& s = *state_;
  s.context = OSMesaCreateContextAttribs(attribs, nullptr);
  if (!s.context) {
    throw InputError("OpenGL", "context",
                     "OSMesa could not create an OpenGL 4.5 core context (needs Mesa >= 20 with llvmpipe; is "
                     "libosmesa6 installed and GALLIUM_DRIVER unset or llvmpipe?)");
  }
  s.default_buffer.assign(4 * kDefaultBufferSide * kDefaultBufferSide, 0);
  if (!OSMesaMakeCurrent(s.context, s.default_buffer.data(), GL_UNSIGNED_BYTE, kDefaultBufferSide, kDefaultBufferSide)) {
    OSMesaDestroyContext(s.context);
    s.context = nullptr;
    throw InputError("OpenGL", "context", "OSMesa could not make its OpenGL context current");
  }
  GLint max_size = 0, max_samples = 0, max_dims[2] = {0, 0};
  glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_size);
  glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
  glGetIntegerv(GL_MAX_VIEWPORT_DIMS, max_dims);
  const int limit = std::min<int>(max_size, std::min(max_dims[0], max_dims[1]));
  if (width > limit || height > limit) {
    OSMesaDestroyContext(s.context);
    s.context = nullptr;
    throw InputError("OpenGL", "image size",
                     std::to_string(width) + " x " + std::to_string(height) + " exceeds the renderer's limit of " +
                         std::to_string(limit) + " pixels a side");
  }
  if (samples > std::max(1, int(max_samples))) {
    OSMesaDestroyContext(s.context);
    s.context = nullptr;
    throw InputError("OpenGL", "samples", "at most " + std::to_string(max_samples) + ", got " + std::to_string(samples));
  }
  s.width = width, s.height = height, s.samples = samples;

  glGenFramebuffers(1, &s.fbo);
  glGenRenderbuffers(1, &s.colour);
  glGenRenderbuffers(1, &s.depth);
  glBindFramebuffer(GL_FRAMEBUFFER, s.fbo);
  glBindRenderbuffer(GL_RENDERBUFFER, s.colour);
  glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples > 1 ? samples : 0, GL_RGBA8, width, height);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, s.colour);
  glBindRenderbuffer(GL_RENDERBUFFER, s.depth);
  glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples > 1 ? samples : 0, GL_DEPTH_COMPONENT24, width, height);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, s.depth);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
    throw RuntimeError("OpenGL: the " + std::to_string(width) + " x " + std::to_string(height) + " framebuffer is incomplete");
  }
  glGenFramebuffers(1, &s.resolve_fbo);
  glGenRenderbuffers(1, &s.resolve_colour);
  glBindFramebuffer(GL_FRAMEBUFFER, s.resolve_fbo);
  glBindRenderbuffer(GL_RENDERBUFFER, s.resolve_colour);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, s.resolve_colour);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw RuntimeError("OpenGL: the resolve framebuffer is incomplete");
  glBindFramebuffer(GL_FRAMEBUFFER, s.fbo);
  glViewport(0, 0, width, height);
  glDisable(GL_DITHER);
}

OffscreenGlContext::~OffscreenGlContext() {
  if (!state_ || !state_->context) return;
  State& s = *state_;
  OSMesaMakeCurrent(s.context, s.default_buffer.data(), GL_UNSIGNED_BYTE, kDefaultBufferSide, kDefaultBufferSide);
  glDeleteFramebuffers(1, &s.fbo);
  glDeleteFramebuffers(1, &s.resolve_fbo);
  GLuint rbs[3] = {s.colour, s.depth, s.resolve_colour};
  glDeleteRenderbuffers(3, rbs);
  OSMesaDestroyContext(s.context);
}

void OffscreenGlContext::make_current() {
  State& s = *state_;
  if (OSMesaGetCurrentContext() != s.context &&
      !OSMesaMakeCurrent(s.context, s.default_buffer.data(), GL_UNSIGNED_BYTE, kDefaultBufferSide, kDefaultBufferSide)) {
    throw RuntimeError("OSMesa: could not make the OpenGL context current");
  }
  glBindFramebuffer(GL_FRAMEBUFFER, s.fbo);
  glViewport(0, 0, s.width, s.height);
}

RgbImage OffscreenGlContext::read_pixels() {
  State& s = *state_;
  glBindFramebuffer(GL_READ_FRAMEBUFFER, s.fbo);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, s.resolve_fbo);
  glBlitFramebuffer(0, 0, s.width, s.height, 0, 0, s.width, s.height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, s.resolve_fbo);
  std::vector<uint8_t> rgba(4 * static_cast<std::size_t>(s.width) * static_cast<std::size_t>(s.height));
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, s.width, s.height, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  glBindFramebuffer(GL_FRAMEBUFFER, s.fbo);
  if (glGetError() != GL_NO_ERROR) throw RuntimeError("OpenGL: reading the picture back failed");
  RgbImage img(s.width, s.height);
  for (int y = 0; y < s.height; ++y) {
    const uint8_t* src = rgba.data() + 4 * static_cast<std::size_t>(s.height - 1 - y) * s.width;  // GL rows go up
    uint8_t* dst = img.pixel(0, y);
    for (int x = 0; x < s.width; ++x) dst[3 * x] = src[4 * x], dst[3 * x + 1] = src[4 * x + 1], dst[3 * x + 2] = src[4 * x + 2];
  }
  return img;
}

void OffscreenGlContext::finish() { glFinish(); }
int OffscreenGlContext::width() const { return state_->width; }
int OffscreenGlContext::height() const { return state_->height; }
int OffscreenGlContext::samples() const { return state_->samples; }

std::string OffscreenGlContext::description() const {
  const auto* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  return std::string(version ? version : "?") + ", " + (renderer ? renderer : "?");
}

}  // namespace ctsurg
