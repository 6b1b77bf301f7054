// libFuzzer target: one image file through read_image_file (image_file_reader.h: verification,
// then ITK). CTSURG_FUZZ_SUFFIX picks the format: .nii (a gzip stream is named .nii.gz), .nrrd or
// .mha. Built three times: fuzz_nifti, fuzz_nrrd, fuzz_metaimage.
#include "ctsurg/preprocess/image_file_reader.h"
#include "fuzz_input_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  std::string name = std::string("input") + CTSURG_FUZZ_SUFFIX;
  if (name == "input.nii" && size >= 2 && data[0] == 0x1f && data[1] == 0x8b) name += ".gz";
  const auto path = ctsurg::fuzz::write_input(name, bytes);
  ctsurg::fuzz::expect_refusal_or_success([&] { ctsurg::read_image_file(path); });
  return 0;
}
