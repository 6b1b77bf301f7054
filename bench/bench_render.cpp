// Frames per second of the render stage at 1024 x 1024 (OSMesa llvmpipe, OpenGL 4.5 core): the
// normal-mapped synthetic organ (tests/render/render_test_scenes.h) at the papers' 31,320 faces and at
// ~300k, each frame a new deformation (positions streamed, tangent frames recomputed on the CPU),
// drawn with and without multisampling, with and without reading the pixels back.
// LP_NUM_THREADS sets llvmpipe's rasteriser threads (default: the cores).
#include <benchmark/benchmark.h>

#include <cmath>

#include "ctsurg/render/camera.h"
#include "ctsurg/render/scene_frame.h"
#include "ctsurg/render/surface_renderer.h"
#include "render_test_scenes.h"

namespace {

// args: segments, rings (faces = 2 segments (rings - 1)), samples, read back (0/1)
void BM_RenderFrame(benchmark::State& state) {
  const int segments = int(state.range(0)), rings = int(state.range(1)), samples = int(state.range(2));
  const bool read_back = state.range(3) != 0;
  const ctsurg::SurfaceMesh surface = ctsurg::test::bumpy_organ_surface(segments, rings, 1024);
  // Two deformed shapes, alternated so every frame streams new positions and new frames.
  std::vector<float> shapes[2] = {surface.vertices, surface.vertices};
  for (std::size_t i = 0; i < surface.vertices.size(); i += 3) {
    shapes[1][i] += 1.5f * std::sin(0.2f * surface.vertices[i + 2]);
    shapes[1][i + 1] -= 2.0f * std::exp(-0.01f * surface.vertices[i + 2] * surface.vertices[i + 2]);
  }
  ctsurg::SurfaceRenderer renderer(surface, 1024, 1024, samples);
  const ctsurg::BoundingSphere bounds = ctsurg::bounding_sphere(surface.vertices.data(), surface.vertex_count());
  const ctsurg::Camera camera =
      ctsurg::frame_camera(bounds, ctsurg::parse_view("anterior"), ctsurg::Projection::perspective, 1024, 1024);
  ctsurg::RenderStyle style;
  ctsurg::SceneFrame frame = ctsurg::rest_scene_frame(surface);
  int64_t k = 0;
  for (auto _ : state) {
    frame.vertices = shapes[k++ & 1].data();
    if (read_back) {
      benchmark::DoNotOptimize(renderer.render(frame, camera, style));
    } else {
      renderer.draw(frame, camera, style);
      renderer.finish();
    }
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["faces"] = double(surface.triangle_count());
  state.counters["fps"] = benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
}

}  // namespace

BENCHMARK(BM_RenderFrame)
    ->ArgNames({"segments", "rings", "samples", "readback"})
    ->Args({180, 88, 1, 0})
    ->Args({180, 88, 4, 0})
    ->Args({180, 88, 4, 1})
    ->Args({560, 270, 1, 0})
    ->Args({560, 270, 4, 0})
    ->Args({560, 270, 4, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2.0);
BENCHMARK_MAIN();
