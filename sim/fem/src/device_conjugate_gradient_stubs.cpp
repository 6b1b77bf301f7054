// DeviceConjugateGradient (device_conjugate_gradient.h) in a build without CUDA (CTSURG_CUDA=OFF or no
// nvcc): the constructor refuses with require_backend's InputError (field "backend": "cuda was asked for
// but this build has no CUDA kernels ..."), so no other member is ever reached. A build with CUDA
// compiles device_conjugate_gradient_cuda.cu instead.
#include "device_conjugate_gradient.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/base/backend.h"

namespace ctsurg::sim {
namespace {
[[noreturn]] void no_cuda_cg() { throw RuntimeError("device conjugate gradient: this build has no CUDA"); }
}  // namespace

struct DeviceConjugateGradient::Device {};

DeviceConjugateGradient::DeviceConjugateGradient(const char* where) { require_backend(Backend::cuda, where); }
DeviceConjugateGradient::~DeviceConjugateGradient() = default;
void DeviceConjugateGradient::set_pattern(int32_t, const int32_t*, const int32_t*) { no_cuda_cg(); }
void DeviceConjugateGradient::set_values(const double*) { no_cuda_cg(); }
DeviceCgResult DeviceConjugateGradient::solve(const double*, double*, double, int64_t) { no_cuda_cg(); }

}  // namespace ctsurg::sim
