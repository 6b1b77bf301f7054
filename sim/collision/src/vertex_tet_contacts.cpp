// The dispatcher of the vertex-tet query (vertex_tet_contacts.h): the checks, once, then the CPU or CUDA
// launchers (collision_backends.h); and the brute-force reference.
#include "ctsurg/sim/collision/vertex_tet_contacts.h"

#include "collision_backends.h"
#include "ctsurg/core/error.h"

#include <cmath>
#include <string>

namespace ctsurg::sim {
namespace {

constexpr const char* kVertexTetWhere = "vertex tet contacts";

// The checked test (the view of the arguments): boxes enlarged by 8 x the tolerance of their largest
// side (contact_tests_impl.h) plus a rounding slack.
VertexTetTest prepare_vertex_tet(std::span<const double> positions, std::span<const uint32_t> tets,
                      std::span<const uint32_t> vertex_object, std::span<const uint32_t> tet_object,
                      double inside_tolerance, ContactPairs pairs, int threads, double* largest) {
  if (threads < 0) throw InputError(kVertexTetWhere, "threads", "must be >= 0, got " + std::to_string(threads));
  if (!(inside_tolerance >= 0 && inside_tolerance <= 0.01))
    throw InputError(kVertexTetWhere, "inside_tolerance", "must be in [0, 0.01], got " + std::to_string(inside_tolerance));
  *largest = collision_detail::check_positions(positions, kVertexTetWhere, threads);
  const int64_t vertices = static_cast<int64_t>(positions.size() / 3);
  collision_detail::check_primitives(tets, 4, vertices, kVertexTetWhere, "tets", threads);
  collision_detail::check_objects(vertex_object, vertices, kVertexTetWhere, "vertex_object");
  collision_detail::check_objects(tet_object, static_cast<int64_t>(tets.size() / 4), kVertexTetWhere, "tet_object");
  const double margin = collision_detail::box_slack(*largest, 0);
  return {{positions.data(), tets.data(), static_cast<int64_t>(tets.size() / 4), 4, margin, 8 * inside_tolerance},
          {vertex_object.data(), tet_object.data(), pairs == ContactPairs::all},
          inside_tolerance};
}

}  // namespace

std::vector<VertexTetContact> vertex_tet_contacts(std::span<const double> positions, std::span<const uint32_t> tets,
                                                  std::span<const uint32_t> vertex_object,
                                                  std::span<const uint32_t> tet_object, const ContactOptions& options,
                                                  double inside_tolerance) {
  require_backend(options.backend, kVertexTetWhere);
  double largest = 0;
  const VertexTetTest test = prepare_vertex_tet(positions, tets, vertex_object, tet_object, inside_tolerance, options.pairs,
                                     options.threads, &largest);
  const double cell = collision_detail::hash_cell_size(positions, tets, 4, options.cell_size, largest,
                                                       test.tets.margin, kVertexTetWhere, options.threads);
  const int64_t vertices = static_cast<int64_t>(positions.size() / 3);
  if (options.backend == Backend::cuda) return collision_detail::vertex_tet_contacts_cuda(test, vertices, cell, kVertexTetWhere);
  const SpatialHash hash = collision_detail::build_hash_cpu(test.tets, cell, kVertexTetWhere, options.threads);
  return collision_detail::vertex_tet_contacts_cpu(hash.view(), test, vertices, options.threads);
}

std::vector<VertexTetContact> vertex_tet_contacts_brute_force(std::span<const double> positions,
                                                              std::span<const uint32_t> tets,
                                                              std::span<const uint32_t> vertex_object,
                                                              std::span<const uint32_t> tet_object, ContactPairs pairs,
                                                              double inside_tolerance) {
  double largest = 0;
  const VertexTetTest test = prepare_vertex_tet(positions, tets, vertex_object, tet_object, inside_tolerance, pairs, 0, &largest);
  std::vector<VertexTetContact> out;
  const uint32_t vertices = static_cast<uint32_t>(positions.size() / 3);
  const uint32_t count = static_cast<uint32_t>(tets.size() / 4);
  for (uint32_t v = 0; v < vertices; ++v)
    for (uint32_t t = 0; t < count; ++t) {
      VertexTetContact c{};
      if (test(v, t, c)) out.push_back(c);
    }
  return out;
}

}  // namespace ctsurg::sim
