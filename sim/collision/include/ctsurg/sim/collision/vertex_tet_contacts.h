// Vertices inside tetrahedra (Teschner et al. 2003's query: a vertex of one object that penetrates
// another object's tets): every (vertex, tet) pair with the vertex inside the tet, found through the
// spatial hash (spatial_hash.h; the tets' boxes, queried with each vertex's cell) and checked exactly
// with barycentric coordinates (kernels/contact_tests_impl.h).
//
// Inside: every barycentric coordinate >= -inside_tolerance, default 1e-9 (a vertex on a face shared by
// two tets is in both; a vertex outside by more than about 1e-9 x the tet's size is in neither).
// Degenerate (flat) tets contain nothing. One vertex array holds every object's vertices; the tets index
// into it. Output sorted by (vertex, tet), the same for any thread count and either backend.
#pragma once

#include "ctsurg/sim/collision/contact_options.h"
#include "ctsurg/sim/collision/kernels/contact_tests_impl.h"

#include <cstdint>
#include <span>
#include <vector>

namespace ctsurg::sim {

constexpr double kDefaultInsideTolerance = 1e-9;

//   positions         #V x 3 row-major, mm (finite; #V < 2^32)
//   tets              #T x 4 row-major vertex indices (< #V)
//   vertex_object     #V object ids
//   tet_object        #T object ids
//   inside_tolerance  on the barycentric coordinates, in [0, 0.01]
// Returns the contacts sorted by (vertex, tet). Throws InputError("vertex tet contacts", <field>, ...)
// for a wrong shape, an index out of range, a value not finite, a tolerance out of range or a negative
// cell size; as require_backend when options.backend cannot run here.
std::vector<VertexTetContact> vertex_tet_contacts(std::span<const double> positions, std::span<const uint32_t> tets,
                                                  std::span<const uint32_t> vertex_object,
                                                  std::span<const uint32_t> tet_object,
                                                  const ContactOptions& options = {},
                                                  double inside_tolerance = kDefaultInsideTolerance);

// The same pairs by testing every (vertex, tet) pair (O(#V #T), serial): the reference of the tests.
std::vector<VertexTetContact> vertex_tet_contacts_brute_force(std::span<const double> positions,
                                                              std::span<const uint32_t> tets,
                                                              std::span<const uint32_t> vertex_object,
                                                              std::span<const uint32_t> tet_object, ContactPairs pairs,
                                                              double inside_tolerance = kDefaultInsideTolerance);

}  // namespace ctsurg::sim
