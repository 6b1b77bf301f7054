// Measures of a triangle surface: the volume it encloses (divergence theorem, mm^3; after a cut, of
// what remains, closed or not) and its area (mm^2). Vertices #V x 3 (mm), triangles #F x 3 vertex ids,
// outward-oriented for a positive volume; sums in double.
#pragma once

#include <cstdint>
#include <vector>

namespace ctsurg::sim {

double enclosed_volume(const std::vector<float>& vertices, const std::vector<uint32_t>& triangles);
double surface_area(const std::vector<float>& vertices, const std::vector<uint32_t>& triangles);

}  // namespace ctsurg::sim
