#include "ctsurg/render/colour_map.h"

#include <algorithm>
#include <cmath>

namespace ctsurg {

std::array<uint8_t, 3> turbo_colour(double t) {
  // Polynomial fit of Turbo published with it (Mikhailov 2019, Google AI blog, "turbo_colormap.glsl").
  const double x = std::clamp(t, 0.0, 1.0);
  const double x2 = x * x, x3 = x2 * x, x4 = x2 * x2, x5 = x4 * x;
  const double r = 0.13572138 + 4.61539260 * x - 42.66032258 * x2 + 132.13108234 * x3 - 152.94239396 * x4 + 59.28637943 * x5;
  const double g = 0.09140261 + 2.19418839 * x + 4.84296658 * x2 - 14.18503333 * x3 + 4.27729857 * x4 + 2.82956604 * x5;
  const double b = 0.10667330 + 12.64194608 * x - 60.58204836 * x2 + 110.36276771 * x3 - 89.90310912 * x4 + 27.34824973 * x5;
  const auto byte = [](double v) { return static_cast<uint8_t>(std::lround(std::clamp(v, 0.0, 1.0) * 255.0)); };
  return {byte(r), byte(g), byte(b)};
}

const std::vector<uint8_t>& turbo_colour_table() {
  static const std::vector<uint8_t> table = [] {
    std::vector<uint8_t> t(256 * 3);
    for (int i = 0; i < 256; ++i) {
      const auto c = turbo_colour(i / 255.0);
      for (int k = 0; k < 3; ++k) t[3 * i + k] = c[k];
    }
    return t;
  }();
  return table;
}

}  // namespace ctsurg
