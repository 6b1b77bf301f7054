// libFuzzer target: another mesher's tet mesh through import_tet_mesh (mesh/tet_mesh_import.h): VTK XML
// .vtu, Gmsh .msh, Medit .mesh, then orientation, degeneracy and duplicate checks, boundary faces and
// quality. CTSURG_FUZZ_SUFFIX picks the format: built three times, fuzz_vtu, fuzz_msh and fuzz_medit.
#include "ctsurg/mesh/tet_mesh_import.h"
#include "fuzz_input_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = ctsurg::fuzz::write_input("input" CTSURG_FUZZ_SUFFIX, std::string_view(reinterpret_cast<const char*>(data), size));
  ctsurg::fuzz::expect_refusal_or_success([&] { (void)ctsurg::import_tet_mesh(path); });
  return 0;
}
