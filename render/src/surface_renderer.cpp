// OpenGL (through OSMesa's entry points) is confined to this file and gl_context.cpp.
#define GL_GLEXT_PROTOTYPES 1
#include "ctsurg/render/surface_renderer.h"

#include <GL/glcorearb.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <string>
#include <unordered_set>

#include "ctsurg/core/error.h"
#include "ctsurg/render/colour_map.h"
#include "ctsurg/render/deformed_tangent_frames.h"

namespace ctsurg {

namespace {

// Vertex texture fetch: positions, normals, tangents and heat values come from buffer textures
// indexed by gl_VertexID; only the texture coordinates are a (rest, uploaded once) vertex attribute.
constexpr const char* kSurfaceVertexShader = R"(#version 450 core
layout(location = 0) in vec2 a_uv;
uniform samplerBuffer u_positions;  // RGB32F, LPS mm
uniform samplerBuffer u_normals;    // RGB32F, unit
uniform samplerBuffer u_tangents;   // RGBA32F, unit xyz + handedness
uniform samplerBuffer u_values;     // R32F, heat-map value in mm
uniform samplerBuffer u_region;     // RG32F, local region: (in the region, on its interface) as 0 / 1
uniform mat4 u_view_projection;
out vec3 v_world;
out vec3 v_normal;
out vec4 v_tangent;
out vec2 v_uv;
out float v_value;
out vec2 v_region;
void main() {
  vec3 p = texelFetch(u_positions, gl_VertexID).xyz;
  v_world = p;
  v_normal = texelFetch(u_normals, gl_VertexID).xyz;
  v_tangent = texelFetch(u_tangents, gl_VertexID);
  v_value = texelFetch(u_values, gl_VertexID).x;
  v_region = texelFetch(u_region, gl_VertexID).xy;
  v_uv = a_uv;
  gl_Position = u_view_projection * vec4(p, 1.0);
}
)";

constexpr const char* kSurfaceFragmentShader = R"(#version 450 core
in vec3 v_world;
in vec3 v_normal;
in vec4 v_tangent;
in vec2 v_uv;
in float v_value;
in vec2 v_region;
uniform sampler2D u_normal_map;  // tangent space, (n + 1) / 2, row 0 at v = 0
uniform sampler1D u_colour_table;  // Turbo, 256 entries
uniform bool u_use_normal_map;
uniform bool u_heat;
uniform float u_heat_max;
uniform bool u_orthographic;
uniform vec3 u_eye;
uniform vec3 u_forward;
uniform vec3 u_key;   // unit, towards the key light (LPS)
uniform vec3 u_fill;  // unit, towards the fill light
uniform vec3 u_tissue;
uniform bool u_wound;  // triangles closing a cut's hole: the incision's inside, not skin
uniform bool u_show_region;  // hatch the local region, darken its interface
uniform vec3 u_region_rgb;
uniform float u_hatch_px;    // stripe width, pixels
out vec4 o_colour;
void main() {
  vec3 n = normalize(v_normal);
  if (u_use_normal_map && !u_wound) {
    // glTF: bitangent = w * cross(normal, tangent), green up the image.
    vec3 t = v_tangent.xyz - n * dot(n, v_tangent.xyz);
    float tl = length(t);
    if (tl > 1e-6) {
      t /= tl;
      vec3 b = (v_tangent.w < 0.0 ? -1.0 : 1.0) * cross(n, t);
      vec3 m = texture(u_normal_map, v_uv).rgb * 2.0 - 1.0;
      n = normalize(m.x * t + m.y * b + m.z * n);
    }
  }
  vec3 albedo = u_tissue;
  if (u_heat) albedo = texture(u_colour_table, clamp(v_value / u_heat_max, 0.0, 1.0) * (255.0 / 256.0) + 0.5 / 256.0).rgb;
  float specular_strength = u_heat ? 0.12 : 0.28;
  if (!gl_FrontFacing) n = -n;  // light the face towards the viewer
  if (!gl_FrontFacing || u_wound) {
    // The inside, seen through a cut or closing one: a darker red.
    albedo = u_heat ? albedo * 0.7 : vec3(0.42, 0.06, 0.08);
    specular_strength = 0.1;
  }
  if (u_show_region) {
    // Past halfway between a region vertex and an outside one: inside. The region in diagonal
    // screen-space stripes of u_region_rgb (strong, weak), so what is under it (tissue, a heat value)
    // still shows; the interface vertices' band on a darkened base; the region's edge (the halfway
    // contour) a dark line about 1.5 pixels wide.
    if (v_region.x > 0.5) {
      // A heat map keeps its colours between the stripes (and under a lighter interface shade).
      float stripe = mod(gl_FragCoord.x + gl_FragCoord.y, 2.0 * u_hatch_px) < u_hatch_px ? (u_heat ? 0.5 : 0.65) : (u_heat ? 0.0 : 0.3);
      if (v_region.y > 0.5) albedo *= u_heat ? 0.7 : 0.45;
      albedo = mix(albedo, u_region_rgb, stripe);
    }
    float edge = abs(v_region.x - 0.5) / max(fwidth(v_region.x), 1e-6);
    if (edge < 0.75) albedo *= 0.15;
  }
  vec3 to_eye = u_orthographic ? -u_forward : normalize(u_eye - v_world);
  float diffuse = 0.72 * max(dot(n, u_key), 0.0) + 0.28 * max(dot(n, u_fill), 0.0) + 0.16;
  vec3 h = normalize(u_key + to_eye);
  float specular = specular_strength * pow(max(dot(n, h), 0.0), 48.0);
  o_colour = vec4(albedo * diffuse + vec3(specular), 1.0);
}
)";

constexpr const char* kToolVertexShader = R"(#version 450 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
uniform vec3 u_centre;
uniform float u_scale;
uniform mat4 u_view_projection;
out vec3 v_normal;
void main() {
  v_normal = a_normal;
  gl_Position = u_view_projection * vec4(u_centre + u_scale * a_position, 1.0);
}
)";

constexpr const char* kToolFragmentShader = R"(#version 450 core
in vec3 v_normal;
uniform vec4 u_colour;
uniform vec3 u_key;
uniform vec3 u_fill;
out vec4 o_colour;
void main() {
  vec3 n = normalize(v_normal);
  if (!gl_FrontFacing) n = -n;
  float diffuse = 0.65 * max(dot(n, u_key), 0.0) + 0.25 * max(dot(n, u_fill), 0.0) + 0.3;
  o_colour = vec4(u_colour.rgb * diffuse, u_colour.a);
}
)";

GLuint compile(GLenum kind, const char* source) {
  const GLuint s = glCreateShader(kind);
  glShaderSource(s, 1, &source, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[4096] = {};
    glGetShaderInfoLog(s, sizeof log, nullptr, log);
    throw RuntimeError(std::string("OpenGL: shader compilation failed: ") + log);
  }
  return s;
}

GLuint link(const char* vs, const char* fs) {
  const GLuint v = compile(GL_VERTEX_SHADER, vs), f = compile(GL_FRAGMENT_SHADER, fs);
  const GLuint p = glCreateProgram();
  glAttachShader(p, v);
  glAttachShader(p, f);
  glLinkProgram(p);
  glDeleteShader(v);
  glDeleteShader(f);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[4096] = {};
    glGetProgramInfoLog(p, sizeof log, nullptr, log);
    throw RuntimeError(std::string("OpenGL: shader linking failed: ") + log);
  }
  return p;
}


// The unit icosphere (two subdivisions, 320 triangles): positions double as normals.
void icosphere(std::vector<float>& xyz, std::vector<uint32_t>& tri) {
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  std::vector<Eigen::Vector3f> p = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                    {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& q : p) q.normalize();
  tri = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6, 7, 1, 8,
         3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
  for (int level = 0; level < 2; ++level) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    const auto midpoint = [&](uint32_t a, uint32_t b) {
      const auto key = std::minmax(a, b);
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      p.push_back((p[a] + p[b]).normalized());
      return mid[key] = static_cast<uint32_t>(p.size() - 1);
    };
    std::vector<uint32_t> next;
    for (std::size_t f = 0; f < tri.size(); f += 3) {
      const uint32_t a = tri[f], b = tri[f + 1], c = tri[f + 2];
      const uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      next.insert(next.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    tri.swap(next);
  }
  xyz.clear();
  for (const auto& q : p) xyz.insert(xyz.end(), {q.x(), q.y(), q.z()});
}

}  // namespace

struct SurfaceRenderer::State {
  // A buffer texture over a buffer object: the streamed per-vertex data.
  struct BufferTexture {
    GLuint buffer = 0, texture = 0;
    void create(GLenum format) {
      glGenBuffers(1, &buffer);
      glGenTextures(1, &texture);
      glBindBuffer(GL_TEXTURE_BUFFER, buffer);
      glBufferData(GL_TEXTURE_BUFFER, 16, nullptr, GL_STREAM_DRAW);
      glBindTexture(GL_TEXTURE_BUFFER, texture);
      glTexBuffer(GL_TEXTURE_BUFFER, format, buffer);
    }
    // Orphans the old storage (no wait on frames still being drawn) and uploads `bytes`.
    void stream(const void* data, std::size_t bytes) {
      glBindBuffer(GL_TEXTURE_BUFFER, buffer);
      glBufferData(GL_TEXTURE_BUFFER, static_cast<GLsizeiptr>(bytes), data, GL_STREAM_DRAW);
    }
    void destroy() {
      glDeleteTextures(1, &texture);
      glDeleteBuffers(1, &buffer);
    }
  };
  OffscreenGlContext context;
  DeformedTangentFrames frames;
  int64_t vertex_count = 0;
  bool has_normal_map = false;
  GLuint surface_program = 0, tool_program = 0;
  GLuint surface_vao = 0, uv_buffer = 0, normal_map = 0, colour_table = 0;
  BufferTexture positions, normals, tangents, values, region;
  struct IndexBuffer {
    GLuint buffer = 0;
    GLsizei count = 0;
    bool closed = false;  // every edge shared by two triangles (seams welded): no back face can show
  };
  std::map<int, IndexBuffer> index_buffers;  // by topology id
  std::vector<uint32_t> weld;                // vertex -> first copy of its source vertex (atlas seams)
  GLuint sphere_vao = 0, sphere_vbo = 0, sphere_ebo = 0;
  GLsizei sphere_indices = 0;
  GLuint blade_vao = 0, blade_vbo = 0;
  std::vector<float> normal_scratch, tangent_scratch, zero_values, region_scratch;

  State(const SurfaceMesh& surface, int width, int height, int samples)
      : context(width, height, samples), frames(surface) {}
};

SurfaceRenderer::SurfaceRenderer(const SurfaceMesh& surface, int width, int height, int samples)
    : state_(std::make_unique<State>(surface, width, height, samples)) {
  State& s = *state_;
  s.context.make_current();
  s.vertex_count = surface.vertex_count();
  s.has_normal_map = !surface.normal_map.empty() && !surface.uvs.empty() && !surface.tangents.empty();
  s.surface_program = link(kSurfaceVertexShader, kSurfaceFragmentShader);
  s.tool_program = link(kToolVertexShader, kToolFragmentShader);

  // Rest data, uploaded once.
  glGenVertexArrays(1, &s.surface_vao);
  glBindVertexArray(s.surface_vao);
  glGenBuffers(1, &s.uv_buffer);
  glBindBuffer(GL_ARRAY_BUFFER, s.uv_buffer);
  const std::vector<float> no_uvs(2 * static_cast<std::size_t>(s.vertex_count), 0.0f);
  const std::vector<float>& uvs = surface.uvs.empty() ? no_uvs : surface.uvs;
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(uvs.size() * sizeof(float)), uvs.data(), GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 0, nullptr);
  s.positions.create(GL_RGB32F);
  s.normals.create(GL_RGB32F);
  s.tangents.create(GL_RGBA32F);
  s.values.create(GL_R32F);
  s.region.create(GL_RG32F);
  s.zero_values.assign(static_cast<std::size_t>(s.vertex_count), 0.0f);
  s.weld.resize(static_cast<std::size_t>(s.vertex_count));
  for (std::size_t v = 0; v < s.weld.size(); ++v) s.weld[v] = static_cast<uint32_t>(v);
  if (surface.source_vertex.size() == s.weld.size() && surface.source_vertex_count > 0) {
    std::vector<int64_t> first(static_cast<std::size_t>(surface.source_vertex_count), -1);
    for (std::size_t v = 0; v < s.weld.size(); ++v) {
      int64_t& f = first[surface.source_vertex[v]];
      if (f < 0) f = static_cast<int64_t>(v);
      s.weld[v] = static_cast<uint32_t>(f);
    }
  }

  glGenTextures(1, &s.normal_map);
  glBindTexture(GL_TEXTURE_2D, s.normal_map);
  if (s.has_normal_map) {
    const NormalMapImage& m = surface.normal_map;
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    if (m.bits == 16) {
      glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB16, GLsizei(m.width), GLsizei(m.height), 0, GL_RGB, GL_UNSIGNED_SHORT, m.rgb.data());
    } else {
      const std::vector<uint8_t> bytes(m.rgb.begin(), m.rgb.end());
      glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, GLsizei(m.width), GLsizei(m.height), 0, GL_RGB, GL_UNSIGNED_BYTE, bytes.data());
    }
    glGenerateMipmap(GL_TEXTURE_2D);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_NEAREST);
  } else {
    const uint8_t flat[3] = {128, 128, 255};
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, 1, 1, 0, GL_RGB, GL_UNSIGNED_BYTE, flat);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  }
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);

  glGenTextures(1, &s.colour_table);
  glBindTexture(GL_TEXTURE_1D, s.colour_table);
  glTexImage1D(GL_TEXTURE_1D, 0, GL_RGB8, 256, 0, GL_RGB, GL_UNSIGNED_BYTE, turbo_colour_table().data());
  glTexParameteri(GL_TEXTURE_1D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_1D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_1D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);

  // Tools: the unit sphere, and a dynamic buffer for blade quads (position, normal interleaved).
  std::vector<float> sphere_xyz;
  std::vector<uint32_t> sphere_tri;
  icosphere(sphere_xyz, sphere_tri);
  glGenVertexArrays(1, &s.sphere_vao);
  glBindVertexArray(s.sphere_vao);
  glGenBuffers(1, &s.sphere_vbo);
  glBindBuffer(GL_ARRAY_BUFFER, s.sphere_vbo);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(sphere_xyz.size() * sizeof(float)), sphere_xyz.data(), GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  glGenBuffers(1, &s.sphere_ebo);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, s.sphere_ebo);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(sphere_tri.size() * sizeof(uint32_t)), sphere_tri.data(),
               GL_STATIC_DRAW);
  s.sphere_indices = static_cast<GLsizei>(sphere_tri.size());
  glGenVertexArrays(1, &s.blade_vao);
  glBindVertexArray(s.blade_vao);
  glGenBuffers(1, &s.blade_vbo);
  glBindBuffer(GL_ARRAY_BUFFER, s.blade_vbo);
  glBufferData(GL_ARRAY_BUFFER, 16, nullptr, GL_STREAM_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), reinterpret_cast<const void*>(3 * sizeof(float)));
  glBindVertexArray(0);
  if (glGetError() != GL_NO_ERROR) throw RuntimeError("OpenGL: uploading the surface failed");
}

SurfaceRenderer::~SurfaceRenderer() {
  if (!state_) return;
  State& s = *state_;
  s.context.make_current();
  for (auto& [id, buffer] : s.index_buffers) glDeleteBuffers(1, &buffer.buffer);
  s.positions.destroy();
  s.normals.destroy();
  s.tangents.destroy();
  s.values.destroy();
  s.region.destroy();
  const GLuint buffers[] = {s.uv_buffer, s.sphere_vbo, s.sphere_ebo, s.blade_vbo};
  glDeleteBuffers(4, buffers);
  const GLuint textures[] = {s.normal_map, s.colour_table};
  glDeleteTextures(2, textures);
  const GLuint arrays[] = {s.surface_vao, s.sphere_vao, s.blade_vao};
  glDeleteVertexArrays(3, arrays);
  glDeleteProgram(s.surface_program);
  glDeleteProgram(s.tool_program);
}

bool SurfaceRenderer::has_normal_map() const { return state_->has_normal_map; }
OffscreenGlContext& SurfaceRenderer::context() { return state_->context; }
void SurfaceRenderer::finish() { state_->context.finish(); }

void SurfaceRenderer::draw(const SceneFrame& frame, const Camera& camera, const RenderStyle& style) {
  State& s = *state_;
  if (!frame.vertices || !frame.triangles) throw RuntimeError("render: the frame has no surface");
  if (!frame.values.empty() && static_cast<int64_t>(frame.values.size()) != s.vertex_count)
    throw RuntimeError("render: the heat-map values do not match the vertices");
  s.context.make_current();
  const std::size_t nv = static_cast<std::size_t>(s.vertex_count);

  // Stream what moves: positions, the deformed frames, heat values.
  s.frames.compute(frame.vertices, *frame.triangles, frame.topology, s.normal_scratch, s.tangent_scratch);
  s.positions.stream(frame.vertices, 3 * nv * sizeof(float));
  s.normals.stream(s.normal_scratch.data(), 3 * nv * sizeof(float));
  if (s.tangent_scratch.empty()) s.tangent_scratch.assign(4 * nv, 0.0f);
  s.tangents.stream(s.tangent_scratch.data(), 4 * nv * sizeof(float));
  const std::vector<float>& values = frame.values.empty() ? s.zero_values : frame.values;
  s.values.stream(values.data(), nv * sizeof(float));
  const bool show_region = style.region && frame.region;
  if (show_region) {
    s.region_scratch.resize(2 * nv);
    for (std::size_t v = 0; v < nv; ++v) {
      s.region_scratch[2 * v] = frame.region[v] >= 1 ? 1.0f : 0.0f;
      s.region_scratch[2 * v + 1] = frame.region[v] == 2 ? 1.0f : 0.0f;
    }
    s.region.stream(s.region_scratch.data(), 2 * nv * sizeof(float));
  }
  auto ib = s.index_buffers.find(frame.topology);
  if (ib == s.index_buffers.end()) {
    GLuint buffer = 0;
    glGenBuffers(1, &buffer);
    glBindVertexArray(s.surface_vao);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, buffer);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(frame.triangles->size() * sizeof(uint32_t)),
                 frame.triangles->data(), GL_STATIC_DRAW);
    // A closed, consistently oriented surface shows no back faces: culling them halves the shading
    // work (llvmpipe shades every fragment that passes the depth test, back faces drawn first included).
    const std::vector<uint32_t>& t = *frame.triangles;
    std::unordered_set<uint64_t> edges;
    edges.reserve(t.size());
    const auto key = [&](uint32_t a, uint32_t b) { return uint64_t(s.weld[a]) << 32 | s.weld[b]; };
    for (std::size_t f = 0; f + 2 < t.size(); f += 3)
      for (int c = 0; c < 3; ++c) edges.insert(key(t[f + c], t[f + (c + 1) % 3]));
    bool closed = !t.empty();
    for (const uint64_t e : edges)
      if (!edges.count(e << 32 | e >> 32)) {
        closed = false;
        break;
      }
    ib = s.index_buffers.emplace(frame.topology, State::IndexBuffer{buffer, static_cast<GLsizei>(t.size()), closed}).first;
  }

  // Lights follow the camera: the key above-left of it, the fill low on the right.
  const Eigen::Vector3d fwd = camera.forward;
  const Eigen::Vector3d right(camera.view(0, 0), camera.view(0, 1), camera.view(0, 2));
  const Eigen::Vector3d up(camera.view(1, 0), camera.view(1, 1), camera.view(1, 2));
  const Eigen::Vector3f key = (-fwd - 0.45 * right + 0.55 * up).normalized().cast<float>();
  const Eigen::Vector3f fill = (-fwd + 0.6 * right - 0.3 * up).normalized().cast<float>();
  const Eigen::Matrix4f vp = camera.projection * camera.view;

  glClearColor(style.background_rgb[0], style.background_rgb[1], style.background_rgb[2], 1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glDisable(GL_BLEND);
  // Two-sided: the inside shows through cuts; a closed surface culls its (hidden) back faces.
  if (ib->second.closed) {
    glEnable(GL_CULL_FACE);
    glCullFace(GL_BACK);
  } else {
    glDisable(GL_CULL_FACE);
  }

  const GLuint p = s.surface_program;
  glUseProgram(p);
  const auto bind_buffer_texture = [&](const char* name, int unit, const State::BufferTexture& b) {
    glActiveTexture(GL_TEXTURE0 + unit);
    glBindTexture(GL_TEXTURE_BUFFER, b.texture);
    glUniform1i(glGetUniformLocation(p, name), unit);
  };
  bind_buffer_texture("u_positions", 0, s.positions);
  bind_buffer_texture("u_normals", 1, s.normals);
  bind_buffer_texture("u_tangents", 2, s.tangents);
  bind_buffer_texture("u_values", 3, s.values);
  bind_buffer_texture("u_region", 6, s.region);
  glActiveTexture(GL_TEXTURE4);
  glBindTexture(GL_TEXTURE_2D, s.normal_map);
  glUniform1i(glGetUniformLocation(p, "u_normal_map"), 4);
  glActiveTexture(GL_TEXTURE5);
  glBindTexture(GL_TEXTURE_1D, s.colour_table);
  glUniform1i(glGetUniformLocation(p, "u_colour_table"), 5);
  glUniform1i(glGetUniformLocation(p, "u_use_normal_map"), style.normal_map && s.has_normal_map);
  glUniform1i(glGetUniformLocation(p, "u_heat"), style.heat_map);
  glUniform1f(glGetUniformLocation(p, "u_heat_max"), style.heat_max_mm > 0.0f ? style.heat_max_mm : 1.0f);
  glUniform1i(glGetUniformLocation(p, "u_orthographic"), camera.projection_kind == Projection::orthographic);
  const Eigen::Vector3f eye = camera.eye.cast<float>(), forward = camera.forward.cast<float>();
  glUniform3fv(glGetUniformLocation(p, "u_eye"), 1, eye.data());
  glUniform3fv(glGetUniformLocation(p, "u_forward"), 1, forward.data());
  glUniform3fv(glGetUniformLocation(p, "u_key"), 1, key.data());
  glUniform3fv(glGetUniformLocation(p, "u_fill"), 1, fill.data());
  glUniform3fv(glGetUniformLocation(p, "u_tissue"), 1, style.tissue_rgb);
  glUniform1i(glGetUniformLocation(p, "u_show_region"), show_region);
  glUniform3fv(glGetUniformLocation(p, "u_region_rgb"), 1, style.region_rgb);
  glUniform1f(glGetUniformLocation(p, "u_hatch_px"), std::max(3.0f, std::round(float(s.context.height()) / 96.0f)));
  glUniformMatrix4fv(glGetUniformLocation(p, "u_view_projection"), 1, GL_FALSE, vp.data());
  glBindVertexArray(s.surface_vao);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ib->second.buffer);
  // The triangles closing cut holes come last: the rest as tissue, then those as the wound's inside.
  const GLsizei closing = static_cast<GLsizei>(std::clamp<int64_t>(3 * frame.closing_triangles, 0, ib->second.count));
  glUniform1i(glGetUniformLocation(p, "u_wound"), 0);
  glDrawElements(GL_TRIANGLES, ib->second.count - closing, GL_UNSIGNED_INT, nullptr);
  if (closing > 0) {
    glUniform1i(glGetUniformLocation(p, "u_wound"), 1);
    glDrawElements(GL_TRIANGLES, closing, GL_UNSIGNED_INT,
                   reinterpret_cast<const void*>(static_cast<std::uintptr_t>(ib->second.count - closing) * sizeof(uint32_t)));
  }

  if (style.tools && (!frame.spheres.empty() || !frame.blades.empty() || !frame.instrument_triangles.empty() ||
                      !frame.stitch_triangles.empty())) {
    // Translucent tools over the opaque surface: blended, depth-tested, not writing depth.
    const GLuint q = s.tool_program;
    glUseProgram(q);
    // A soup of triangles (#3T corners x (position LPS mm, unit normal)) in one colour, through the
    // blade buffer, placed as they are (no centre, unit scale).
    const auto draw_soup = [&](const std::vector<float>& corners, const float* colour) {
      glBindVertexArray(s.blade_vao);
      glBindBuffer(GL_ARRAY_BUFFER, s.blade_vbo);
      glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(corners.size() * sizeof(float)), corners.data(), GL_STREAM_DRAW);
      const float zero[3] = {0.0f, 0.0f, 0.0f};
      glUniform4fv(glGetUniformLocation(q, "u_colour"), 1, colour);
      glUniform3fv(glGetUniformLocation(q, "u_centre"), 1, zero);
      glUniform1f(glGetUniformLocation(q, "u_scale"), 1.0f);
      glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(corners.size() / 6));
    };
    const float steel_blade[4] = {0.78f, 0.8f, 0.84f, 0.6f}, steel_instrument[4] = {0.72f, 0.74f, 0.78f, 0.85f},
                violet[4] = {0.42f, 0.2f, 0.75f, 1.0f};
    glUniformMatrix4fv(glGetUniformLocation(q, "u_view_projection"), 1, GL_FALSE, vp.data());
    glUniform3fv(glGetUniformLocation(q, "u_key"), 1, key.data());
    glUniform3fv(glGetUniformLocation(q, "u_fill"), 1, fill.data());
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    glDepthMask(GL_FALSE);
    glEnable(GL_CULL_FACE);
    glCullFace(GL_BACK);
    glBindVertexArray(s.sphere_vao);
    for (const ToolSphere& t : frame.spheres) {
      const float colour[4] = {t.grab ? 0.25f : 0.3f, t.grab ? 0.85f : 0.55f, t.grab ? 0.35f : 0.95f, 0.42f};
      glUniform4fv(glGetUniformLocation(q, "u_colour"), 1, colour);
      glUniform3fv(glGetUniformLocation(q, "u_centre"), 1, t.centre);
      glUniform1f(glGetUniformLocation(q, "u_scale"), t.radius);
      glDrawElements(GL_TRIANGLES, s.sphere_indices, GL_UNSIGNED_INT, nullptr);
    }
    glDisable(GL_CULL_FACE);
    if (!frame.blades.empty()) {
      // Each blade: a quad on its cutting edge whose back (40 % of the edge's length) points away from
      // the organ (from the mean of a sample of the vertices), so a blade in a cut is seen edge-on
      // from outside and does not hide the incision.
      std::vector<float> quads;
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      const std::size_t step = std::max<std::size_t>(1, nv / 512);
      std::size_t used = 0;
      for (std::size_t v = 0; v < nv; v += step, ++used)
        mean += Eigen::Vector3d(frame.vertices[3 * v], frame.vertices[3 * v + 1], frame.vertices[3 * v + 2]);
      mean /= double(std::max<std::size_t>(used, 1));
      for (const ToolBlade& b : frame.blades) {
        const Eigen::Vector3d a(b.a[0], b.a[1], b.a[2]), e(b.b[0], b.b[1], b.b[2]);
        const Eigen::Vector3d edge = e - a;
        const Eigen::Vector3d axis = edge.norm() > 0.0 ? Eigen::Vector3d(edge.normalized()) : Eigen::Vector3d::UnitZ();
        const Eigen::Vector3d out = 0.5 * (a + e) - mean;
        Eigen::Vector3d side = out - axis * axis.dot(out);
        if (side.norm() < 1e-9 * std::max(1.0, out.norm())) side = axis.cross(camera.forward);
        if (side.norm() < 1e-12) side = axis.unitOrthogonal();
        side.normalize();
        const Eigen::Vector3d h = side * 0.4 * edge.norm();
        const Eigen::Vector3d n = edge.cross(h).normalized();
        const Eigen::Vector3d corners[6] = {a, e, e + h, a, e + h, a + h};
        for (const auto& c : corners) quads.insert(quads.end(), {float(c.x()), float(c.y()), float(c.z()), float(n.x()), float(n.y()), float(n.z())});
      }
      draw_soup(quads, steel_blade);
    }
    if (!frame.instrument_triangles.empty()) {
      // Instruments: steel, nearly opaque, their back faces culled (closed meshes wound outwards).
      glEnable(GL_CULL_FACE);
      glCullFace(GL_BACK);
      draw_soup(frame.instrument_triangles, steel_instrument);
      glDisable(GL_CULL_FACE);
    }
    // Stitches: opaque violet (the colour of dyed absorbable sutures, seen against red tissue).
    if (!frame.stitch_triangles.empty()) draw_soup(frame.stitch_triangles, violet);
    glDepthMask(GL_TRUE);
    glDisable(GL_BLEND);
  }
  glBindVertexArray(0);
  if (glGetError() != GL_NO_ERROR) throw RuntimeError("OpenGL: drawing the frame failed");
}

RgbImage SurfaceRenderer::render(const SceneFrame& frame, const Camera& camera, const RenderStyle& style) {
  draw(frame, camera, style);
  return state_->context.read_pixels();
}

}  // namespace ctsurg
