#include "ctsurg/core/finite_values.h"

#include "ctsurg/core/error.h"

#include <cmath>
#include <sstream>

namespace ctsurg {

namespace {

template <class T>
void require_finite_impl(std::span<const T> values, std::size_t row_width, const std::string& file,
                         const std::string& field) {
  const std::size_t width = row_width == 0 ? 1 : row_width;
  for (std::size_t n = 0; n < values.size(); ++n) {
    if (std::isfinite(values[n])) continue;
    std::ostringstream s;
    s << (std::isnan(values[n]) ? "NaN" : "an infinite value") << " at ";
    if (width == 1) {
      s << "index " << n;
    } else {
      s << "row " << n / width << ", column " << n % width;
    }
    s << " (every value must be finite)";
    throw InputError(file, field, s.str());
  }
}

}  // namespace

void require_finite(std::span<const float> values, std::size_t row_width, const std::string& file, const std::string& field) {
  require_finite_impl(values, row_width, file, field);
}

void require_finite(std::span<const double> values, std::size_t row_width, const std::string& file,
                    const std::string& field) {
  require_finite_impl(values, row_width, file, field);
}

}  // namespace ctsurg
