// Approximate particle normals (Mosegaard & Sorensen 2005, eq. 5): the normalised sum of the unit
// vectors pointing from a particle's neighbours to it, n_i = normalize(sum_j (x_i - x_j) / |x_i - x_j|).
// The sum comes from the spring-force gather (spring_forces_impl.h); a (near) zero sum, |sum| < 1e-3 (an
// interior particle of a symmetric neighbourhood, or no spring), gives the zero vector, never NaN.
#pragma once

#include "ctsurg/sim/base/kernels/kernel_support.h"

#include <cstdint>

namespace ctsurg::sim {

CTSURG_HD inline void write_normal(Real ux, Real uy, Real uz, Real* nx, Real* ny, Real* nz, int32_t i) {
  const Real len2 = ux * ux + uy * uy + uz * uz;
  // Below 1e-3 the sum is rounding noise of cancelling pairs (an interior particle: the sum of its
  // unit vectors is ~1e-7, a surface particle's is >= 1), not a direction.
  const bool nonzero = len2 > Real(1e-6);
  const Real inv = nonzero ? Real(1) / kernel_sqrt(nonzero ? len2 : Real(1)) : Real(0);
  nx[i] = ux * inv, ny[i] = uy * inv, nz[i] = uz * inv;
}

}  // namespace ctsurg::sim
