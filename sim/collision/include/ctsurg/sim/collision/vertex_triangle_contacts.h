// Proximity of vertices to triangles (Teschner et al. 2003's vertex query with a distance): every
// (vertex, triangle) pair with the vertex within `distance` of the triangle, found through the spatial
// hash (spatial_hash.h; the triangles' boxes enlarged by the distance, queried with each vertex's cell)
// and checked exactly (the closest point on the triangle, Ericson 2005, 5.1.5; kernels/contact_tests_impl.h).
//
// One vertex array holds every object's vertices (organs concatenated); the triangles index into it. The
// table is rebuilt on every call (deforming meshes): O(#V + #F) per call with Teschner's cell size.
// Output sorted by (vertex, triangle): the same records in the same order for any thread count and
// on either backend (the CUDA kernels are the CPU's per-index functions, compiled without FMA
// contraction on both sides, so the doubles agree bit for bit).
#pragma once

#include "ctsurg/sim/collision/contact_options.h"
#include "ctsurg/sim/collision/kernels/contact_tests_impl.h"

#include <cstdint>
#include <span>
#include <vector>

namespace ctsurg::sim {

//   positions        #V x 3 row-major, mm (finite; #V < 2^32)
//   triangles        #F x 3 row-major vertex indices (< #V)
//   vertex_object    #V object ids
//   triangle_object  #F object ids
//   distance         mm, >= 0 and finite: pairs with |vertex - closest point| <= distance
// Returns the contacts sorted by (vertex, triangle). Throws InputError("vertex triangle contacts",
// <field>, ...) for a wrong shape, an index out of range, a value not finite, a negative distance or
// cell size; as require_backend when options.backend cannot run here.
std::vector<VertexTriangleContact> vertex_triangle_contacts(std::span<const double> positions,
                                                            std::span<const uint32_t> triangles,
                                                            std::span<const uint32_t> vertex_object,
                                                            std::span<const uint32_t> triangle_object, double distance,
                                                            const ContactOptions& options = {});

// The same pairs by testing every (vertex, triangle) pair (O(#V #F), serial): the reference of the tests
// and benchmarks. Same arguments and checks; no backend.
std::vector<VertexTriangleContact> vertex_triangle_contacts_brute_force(std::span<const double> positions,
                                                                        std::span<const uint32_t> triangles,
                                                                        std::span<const uint32_t> vertex_object,
                                                                        std::span<const uint32_t> triangle_object,
                                                                        double distance, ContactPairs pairs);

}  // namespace ctsurg::sim
