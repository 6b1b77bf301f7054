// NaN and infinity stop at stage boundaries: every reader checks the floating-point arrays it
// reads and every writer the arrays it writes, so a non-finite value never travels from one tool
// to the next (a NaN vertex would become a NaN trajectory, a NaN voxel a NaN surface).
#pragma once

#include <cstddef>
#include <span>
#include <string>

namespace ctsurg {

// InputError(file, field, ...) naming the first non-finite value by row and column when `values`
// (rows of `row_width` values, row-major) holds NaN or infinity.
void require_finite(std::span<const float> values, std::size_t row_width, const std::string& file, const std::string& field);
void require_finite(std::span<const double> values, std::size_t row_width, const std::string& file, const std::string& field);

}  // namespace ctsurg
