#include "ctsurg/sim/surface/surface_measures.h"

#include <cmath>

namespace ctsurg::sim {

double enclosed_volume(const std::vector<float>& v, const std::vector<uint32_t>& tri) {
  double vol = 0;
  for (size_t f = 0; f < tri.size(); f += 3) {
    const float* a = &v[3 * tri[f]];
    const float* b = &v[3 * tri[f + 1]];
    const float* c = &v[3 * tri[f + 2]];
    vol += (double(a[0]) * (double(b[1]) * c[2] - double(b[2]) * c[1]) - double(a[1]) * (double(b[0]) * c[2] - double(b[2]) * c[0]) +
            double(a[2]) * (double(b[0]) * c[1] - double(b[1]) * c[0])) / 6.0;
  }
  return vol;
}

double surface_area(const std::vector<float>& v, const std::vector<uint32_t>& tri) {
  double area = 0;
  for (size_t f = 0; f < tri.size(); f += 3) {
    const float* a = &v[3 * tri[f]];
    const float* b = &v[3 * tri[f + 1]];
    const float* c = &v[3 * tri[f + 2]];
    const double u[3] = {double(b[0]) - a[0], double(b[1]) - a[1], double(b[2]) - a[2]};
    const double w[3] = {double(c[0]) - a[0], double(c[1]) - a[1], double(c[2]) - a[2]};
    const double x = u[1] * w[2] - u[2] * w[1], y = u[2] * w[0] - u[0] * w[2], z = u[0] * w[1] - u[1] * w[0];
    area += 0.5 * std::sqrt(x * x + y * y + z * z);
  }
  return area;
}

}  // namespace ctsurg::sim
