// What ctsurg verifies in DICOM files before GDCM reads them (dicom_file_check.h): element lengths
// that run past the end of the file are refused, naming the element; well-formed files pass.
#include "ctsurg/preprocess/dicom_file_check.h"

#include "ctsurg/core/error.h"
#include "ctsurg/preprocess/dicom_series_reader.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>

namespace fs = std::filesystem;
using namespace ctsurg;

namespace {

// A fuzz_dicom_folder input (a 4-byte length, the first file, the second) as a folder of two files.
fs::path unpack_series(const test::TempDir& tmp, const std::string& name) {
  const std::string input = test::read_bytes(test::source_dir() / "tests" / "fuzz_regressions" / "fuzz_dicom_folder" / name);
  uint32_t first = 0;
  if (input.size() >= 4) std::memcpy(&first, input.data(), 4);
  EXPECT_TRUE(input.size() >= 4 && first <= input.size() - 4) << name;
  const fs::path dir = tmp / name;
  fs::create_directory(dir);
  std::ofstream(dir / "a.dcm", std::ios::binary) << input.substr(4, first);
  std::ofstream(dir / "b.dcm", std::ios::binary) << input.substr(4 + first);
  return dir;
}

}  // namespace

// Fuzz findings (tests/fuzz_regressions/README.md): a 1 KB slice whose element declares 3 GB (GDCM
// allocated and zeroed it), and slices on which GDCM's own assertions aborted the process. The
// first is refused by the element walk, naming the element; all are refused, none crashes.
// (A length that runs past the end: CtsurgImport.CorruptOrTruncatedDicomSliceIsNamedNotSkipped.)
TEST(DicomFileCheck, FuzzFindingsAreRefused) {
  test::TempDir tmp;
  try {
    read_dicom_series(unpack_series(tmp, "oom-fc9ca85b"), {});
    ADD_FAILURE() << "the folder was read";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field().front(), '(') << "the element is not named: " << e.what();
  }
  for (const char* name : {"crash-18ac66ea", "crash-a1e162ed"}) {
    EXPECT_THROW(read_dicom_series(unpack_series(tmp, name), {}), InputError) << name;
  }
}

TEST(DicomFileCheck, RealSlicesAndOtherFilesPass) {
  test::TempDir tmp;
  std::ofstream(tmp / "notes.txt") << "not DICOM";
  EXPECT_NO_THROW(check_dicom_element_lengths(tmp / "notes.txt"));
  CTSURG_REQUIRE_SHARED_DATA();
  for (const char* series : {"GE", "Philips_S21570_S2010"}) {
    for (const auto& e : fs::directory_iterator(test::shared_data_dir() / "dicom_qa" / series)) {
      EXPECT_NO_THROW(check_dicom_element_lengths(e.path())) << e.path();
    }
  }
  for (const auto& e : fs::directory_iterator(test::shared_data_dir() / "abdomen" / "dicom_j2k")) {
    EXPECT_NO_THROW(check_dicom_element_lengths(e.path())) << e.path();  // encapsulated JPEG 2000
  }
}
