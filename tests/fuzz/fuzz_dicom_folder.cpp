// libFuzzer target: a two-slice DICOM folder through read_dicom_series (dicom_series_reader.h:
// ctsurg's element-length walk, GDCM's scan, ctsurg's header checks and slice ordering, ITK's
// decoding). A series needs two slices, so an input is two files: a 4-byte little-endian length,
// the first file, then the second.
//
// The reader runs GDCM in a child process (isolated_call.h), where libFuzzer sees no coverage, so
// the element walk ctsurg does before GDCM also runs here in-process, and a refusal that carries a
// sanitizer report from the child (ctsurg's or a library's memory error, not a library's own
// assertion) is turned back into a finding.
#include "ctsurg/preprocess/dicom_file_check.h"
#include "ctsurg/preprocess/dicom_series_reader.h"
#include "fuzz_input_file.h"

#include <cstdio>
#include <cstring>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 4) return 0;
  uint32_t first = 0;
  std::memcpy(&first, data, 4);
  const std::string_view rest(reinterpret_cast<const char*>(data) + 4, size - 4);
  if (first > rest.size()) return 0;
  const auto dir = ctsurg::fuzz::folder() / "series";
  std::filesystem::create_directories(dir);
  const auto a = ctsurg::fuzz::write_input("series/a.dcm", rest.substr(0, first));
  const auto b = ctsurg::fuzz::write_input("series/b.dcm", rest.substr(first));
  ctsurg::fuzz::expect_refusal_or_success([&] {
    ctsurg::check_dicom_element_lengths(a);
    ctsurg::check_dicom_element_lengths(b);
  });
  try {
    ctsurg::read_dicom_series(dir, {});
  } catch (const ctsurg::InputError& e) {
    const std::string why = e.problem();
    if (why.find("Sanitizer") != std::string::npos || why.find("runtime error:") != std::string::npos) {
      std::fprintf(stderr, "sanitizer report from the reading process: %s\n", why.c_str());
      std::abort();
    }
  } catch (const ctsurg::RuntimeError&) {
  }
  return 0;
}
