// Triangle meshes other programs write: STL (ASCII or binary), Wavefront OBJ and PLY (ASCII or
// binary), read with assimp. The instruments' shapes come in these formats (sim/base/instrument.h).
//
// assimp runs in a child process (isolated_call.h): its parsers have crashed on damaged files and a
// crash must become a refusal naming the file, not the death of the tool. Its silence is not taken as
// a check: the result is checked here (finite coordinates, indices in range, triangles only, sizes
// bounded); what a shape must be to be an instrument (closed, no degenerate faces) is the caller's
// check (instrument.h).
//
// Vertices with identical coordinates (STL stores each triangle's corners separately) are joined, so
// that the mesh's edges can be matched: faces sharing an edge share its vertex indices.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

namespace ctsurg {

struct TriangleMesh {
  std::vector<double> vertices;   // #V x 3, the file's units (ctsurg: mm)
  std::vector<uint32_t> faces;    // #F x 3 indices into vertices, the file's winding
};

// Bounds on what a reader accepts (a file over them is refused before it is read whole).
inline constexpr int64_t kMaxTriangleMeshFaces = 2'000'000;
inline constexpr std::uintmax_t kMaxTriangleMeshFileBytes = 512ull << 20;

// Reads `path` (.stl, .obj or .ply, by its extension, case-insensitive). InputError naming the file
// (and the field: "extension", "faces", "vertices") when it cannot be read, holds no triangle, holds
// a polygon that is not a triangle or a line or point primitive, holds a non-finite coordinate or is
// over the bounds above.
TriangleMesh read_triangle_mesh(const std::filesystem::path& path);

}  // namespace ctsurg
