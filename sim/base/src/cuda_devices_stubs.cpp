// The CUDA devices in a build without CUDA (CTSURG_CUDA=OFF or no nvcc): there are none, and asking
// for one's description says why (require_backend's message). A build with CUDA compiles
// cuda_devices.cu instead.
#include "ctsurg/sim/base/backend.h"

namespace ctsurg::sim {

int cuda_device_count() { return 0; }

DeviceInfo cuda_device_info(int) {
  require_backend(Backend::cuda, "cuda device");
  return {};
}

}  // namespace ctsurg::sim
