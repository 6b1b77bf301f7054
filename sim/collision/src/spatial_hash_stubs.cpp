// The CUDA launchers of the contact queries (collision_backends.h) in a build without CUDA (CTSURG_CUDA=OFF
// or no nvcc): they refuse with require_backend's InputError (field "backend": "cuda was asked for but
// this build has no CUDA kernels ..."). The dispatchers call require_backend first, so these are a
// second guard. A build with CUDA compiles spatial_hash_cuda.cu instead.
#include "collision_backends.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/base/backend.h"

namespace ctsurg::sim::collision_detail {
namespace {
[[noreturn]] void refuse(const char* where) {
  require_backend(Backend::cuda, where);
  throw RuntimeError(std::string(where) + ": this build has no CUDA");
}
}  // namespace

std::vector<VertexTriangleContact> vertex_triangle_contacts_cuda(const VertexTriangleTest&, int64_t, double,
                                                                 const char* where) {
  refuse(where);
}
std::vector<VertexTetContact> vertex_tet_contacts_cuda(const VertexTetTest&, int64_t, double, const char* where) {
  refuse(where);
}

}  // namespace ctsurg::sim::collision_detail
