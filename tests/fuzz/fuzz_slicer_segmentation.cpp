// libFuzzer target: a 3D Slicer segmentation (.seg.nrrd) through read_slicer_segmentation: ctsurg's own
// NRRD header, segment fields, gzip/raw/ascii data and layer merging (preprocess/slicer_segmentation.h).
#include "ctsurg/preprocess/slicer_segmentation.h"
#include "fuzz_input_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = ctsurg::fuzz::write_input("input.seg.nrrd", std::string_view(reinterpret_cast<const char*>(data), size));
  ctsurg::fuzz::expect_refusal_or_success([&] { (void)ctsurg::read_slicer_segmentation(path); });
  return 0;
}
