// Precision in one place (STYLE.md rule 9) and the host/device qualifier of kernel functions.
//
// Real is the type of every dynamic quantity a kernel reads or writes (positions, masses, forces,
// stiffnesses): float, as in the spring-mass papers (Mosegaard & Sorensen 2005 store positions as
// 32-bit floats in textures). References and tests use double.
//
// CTSURG_HD marks a function that is compiled for the host and, under nvcc, for the device. Bodies
// of CTSURG_HD functions (the *_impl.h kernels) use no std:: containers, no exceptions and no
// virtual calls, so that a *_cuda.cu file can include them unchanged.
#pragma once

#if defined(__CUDACC__)
#define CTSURG_HD __host__ __device__
#else
#define CTSURG_HD
#endif

namespace ctsurg::sim {

using Real = float;

}  // namespace ctsurg::sim
