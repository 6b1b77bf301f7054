// libFuzzer target: one triangle mesh file (an instrument's shape) through read_triangle_mesh: assimp in
// a child process, then ctsurg's checks of what it returned. CTSURG_FUZZ_SUFFIX picks the format:
// built three times, fuzz_stl, fuzz_obj and fuzz_ply.
#include "ctsurg/core/triangle_mesh_file.h"
#include "fuzz_input_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = ctsurg::fuzz::write_input("input" CTSURG_FUZZ_SUFFIX, std::string_view(reinterpret_cast<const char*>(data), size));
  ctsurg::fuzz::expect_refusal_or_success([&] { (void)ctsurg::read_triangle_mesh(path); });
  return 0;
}
