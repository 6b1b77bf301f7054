// The dispatcher of the vertex-triangle query (vertex_triangle_contacts.h): the checks, once, then the
// CPU or CUDA launchers (collision_backends.h); and the brute-force reference.
#include "ctsurg/sim/collision/vertex_triangle_contacts.h"

#include "collision_backends.h"
#include "ctsurg/core/error.h"

#include <cmath>
#include <string>

namespace ctsurg::sim {
namespace {

constexpr const char* kVertexTriangleWhere = "vertex triangle contacts";

// The checked test (the view of the arguments) and the slack-enlarged margin.
VertexTriangleTest prepare_vertex_triangle(std::span<const double> positions, std::span<const uint32_t> triangles,
                           std::span<const uint32_t> vertex_object, std::span<const uint32_t> triangle_object,
                           double distance, ContactPairs pairs, int threads, double* largest) {
  if (threads < 0) throw InputError(kVertexTriangleWhere, "threads", "must be >= 0, got " + std::to_string(threads));
  if (!std::isfinite(distance) || distance < 0)
    throw InputError(kVertexTriangleWhere, "distance", "must be finite and >= 0 mm, got " + std::to_string(distance));
  *largest = collision_detail::check_positions(positions, kVertexTriangleWhere, threads);
  const int64_t vertices = static_cast<int64_t>(positions.size() / 3);
  collision_detail::check_primitives(triangles, 3, vertices, kVertexTriangleWhere, "triangles", threads);
  collision_detail::check_objects(vertex_object, vertices, kVertexTriangleWhere, "vertex_object");
  collision_detail::check_objects(triangle_object, static_cast<int64_t>(triangles.size() / 3), kVertexTriangleWhere,
                                  "triangle_object");
  const double margin = distance + collision_detail::box_slack(*largest, distance);
  return {{positions.data(), triangles.data(), static_cast<int64_t>(triangles.size() / 3), 3, margin, 0},
          {vertex_object.data(), triangle_object.data(), pairs == ContactPairs::all},
          distance};
}

}  // namespace

std::vector<VertexTriangleContact> vertex_triangle_contacts(std::span<const double> positions,
                                                            std::span<const uint32_t> triangles,
                                                            std::span<const uint32_t> vertex_object,
                                                            std::span<const uint32_t> triangle_object, double distance,
                                                            const ContactOptions& options) {
  require_backend(options.backend, kVertexTriangleWhere);
  double largest = 0;
  const VertexTriangleTest test = prepare_vertex_triangle(positions, triangles, vertex_object, triangle_object, distance,
                                          options.pairs, options.threads, &largest);
  const double cell = collision_detail::hash_cell_size(positions, triangles, 3, options.cell_size, largest,
                                                       test.triangles.margin, kVertexTriangleWhere, options.threads);
  const int64_t vertices = static_cast<int64_t>(positions.size() / 3);
  if (options.backend == Backend::cuda)
    return collision_detail::vertex_triangle_contacts_cuda(test, vertices, cell, kVertexTriangleWhere);
  const SpatialHash hash = collision_detail::build_hash_cpu(test.triangles, cell, kVertexTriangleWhere, options.threads);
  return collision_detail::vertex_triangle_contacts_cpu(hash.view(), test, vertices, options.threads);
}

std::vector<VertexTriangleContact> vertex_triangle_contacts_brute_force(std::span<const double> positions,
                                                                        std::span<const uint32_t> triangles,
                                                                        std::span<const uint32_t> vertex_object,
                                                                        std::span<const uint32_t> triangle_object,
                                                                        double distance, ContactPairs pairs) {
  double largest = 0;
  const VertexTriangleTest test =
      prepare_vertex_triangle(positions, triangles, vertex_object, triangle_object, distance, pairs, 0, &largest);
  std::vector<VertexTriangleContact> out;
  const uint32_t vertices = static_cast<uint32_t>(positions.size() / 3);
  const uint32_t count = static_cast<uint32_t>(triangles.size() / 3);
  for (uint32_t v = 0; v < vertices; ++v)
    for (uint32_t t = 0; t < count; ++t) {
      VertexTriangleContact c{};
      if (test(v, t, c)) out.push_back(c);
    }
  return out;
}

}  // namespace ctsurg::sim
