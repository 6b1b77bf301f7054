// libFuzzer target: one ctsurg HDF5 file through its reader (libhdf5 with checksums, then ctsurg's
// format, shape, index, geometry and finiteness checks). CTSURG_FUZZ_READER picks the reader:
// built six times, fuzz_hu_volume_file .. fuzz_trajectory_file and fuzz_centerline_file.
#include "ctsurg/core/centerline_file.h"
#include "ctsurg/core/hu_volume_file.h"
#include "ctsurg/core/occupancy_grid_file.h"
#include "ctsurg/core/surface_mesh_file.h"
#include "ctsurg/core/tet_mesh_file.h"
#include "ctsurg/core/trajectory_file.h"
#include "fuzz_input_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = ctsurg::fuzz::write_input("input.h5", std::string_view(reinterpret_cast<const char*>(data), size));
  ctsurg::fuzz::expect_refusal_or_success([&] { (void)ctsurg::CTSURG_FUZZ_READER(path); });
  return 0;
}
