// What the dispatchers (spatial_hash.cpp, vertex_triangle_contacts.cpp, vertex_tet_contacts.cpp) share:
// the argument checks, the cell size rule, and the CPU (collision_cpu.cpp) and CUDA
// (spatial_hash_cuda.cu, or spatial_hash_stubs.cpp without CUDA) launchers, which trust their arguments.
#pragma once

#include "ctsurg/sim/collision/kernels/contact_tests_impl.h"
#include "ctsurg/sim/collision/spatial_hash.h"

#include <cstdint>
#include <span>
#include <vector>

namespace ctsurg::sim::collision_detail {

// Throws InputError(where, "positions", ...) unless #V x 3 with #V < 2^32 and every value finite;
// returns the largest |coordinate| (mm).
double check_positions(std::span<const double> positions, const char* where, int threads);
// Throws InputError(where, field, ...) unless #P x corners with #P < 2^32 and every index < vertices.
void check_primitives(std::span<const uint32_t> primitives, int corners, int64_t vertices, const char* where,
                      const char* field, int threads);
// Throws InputError(where, field, ...) unless ids has `count` entries.
void check_objects(std::span<const uint32_t> ids, int64_t count, const char* where, const char* field);
// The cell edge: `requested` (> 0), else the primitives' average edge length (1 mm when that is 0), at
// least 2^-18 of the largest |coordinate| + margin. Throws
// InputError(where, "cell_size", ...) for a negative or non-finite request, or one so small that the
// largest |coordinate| + margin is more than 2^19 cells from the origin (so that cell coordinates and a
// box's cell count fit in 64 bits).
double hash_cell_size(std::span<const double> positions, std::span<const uint32_t> primitives, int corners,
                      double requested, double max_abs_coordinate, double margin, const char* where, int threads);
// average_edge_length (spatial_hash.h) without its checks.
double average_edge_length_unchecked(std::span<const double> positions, std::span<const uint32_t> primitives,
                                     int corners, int threads);
// The rounding slack added to box margins: far above the rounding of lo - margin at these coordinates.
inline double box_slack(double max_abs_coordinate, double margin) { return 1e-12 * (max_abs_coordinate + margin); }
// Throws InputError(where, "cell_size", ...) when the boxes cover more than 2^31 - 1 cells.
void check_entry_count(int64_t entries, const char* where);

// CPU (OpenMP).
SpatialHash build_hash_cpu(const HashedPrimitivesView& primitives, double cell_size, const char* where, int threads);
std::vector<VertexTriangleContact> vertex_triangle_contacts_cpu(const HashTableView& table, const VertexTriangleTest& test,
                                                                int64_t vertices, int threads);
std::vector<VertexTetContact> vertex_tet_contacts_cpu(const HashTableView& table, const VertexTetTest& test,
                                                      int64_t vertices, int threads);

// CUDA device 0 (host arrays in, host records out; the table is built on the device). Without CUDA
// (spatial_hash_stubs.cpp) they throw as require_backend.
std::vector<VertexTriangleContact> vertex_triangle_contacts_cuda(const VertexTriangleTest& test, int64_t vertices,
                                                                 double cell_size, const char* where);
std::vector<VertexTetContact> vertex_tet_contacts_cuda(const VertexTetTest& test, int64_t vertices, double cell_size,
                                                       const char* where);

}  // namespace ctsurg::sim::collision_detail
