// Small helpers shared by the *_impl.h kernels (host and device).
#pragma once

#include "ctsurg/sim/base/real.h"

#include <math.h>

#if defined(__CUDACC__)
#define CTSURG_UNROLL _Pragma("unroll")
#elif defined(__GNUC__) && !defined(__clang__)
#define CTSURG_UNROLL _Pragma("GCC unroll 32")
#else
#define CTSURG_UNROLL
#endif

namespace ctsurg::sim {

// Square roots in the kernels' precision (sqrtf for float: no promotion to double on host or device).
CTSURG_HD inline float kernel_sqrt(float v) { return sqrtf(v); }
CTSURG_HD inline double kernel_sqrt(double v) { return sqrt(v); }

}  // namespace ctsurg::sim
