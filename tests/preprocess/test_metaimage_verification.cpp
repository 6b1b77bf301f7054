// What ctsurg verifies in MetaImage files before ITK reads them (metaimage_verification.h): each
// MetaImage defect of issue 17 on a hand-made file, refused with the field that has it.
#include "ctsurg/preprocess/metaimage_verification.h"

#include "ctsurg/core/error.h"
#include "ctsurg/preprocess/image_file_reader.h"
#include "mhd_writer.h"
#include "reader_refusal.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <fstream>

namespace fs = std::filesystem;
using namespace ctsurg;

namespace {

void expect_mha_refused(const fs::path& path, const std::string& field, const std::string& mention = "") {
  test::expect_refused(path, [](const fs::path& p) { verify_metaimage_file(p, false); }, field, mention, true);
}

const std::string kHeader =
    "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\nDimSize = 3 3 3\n"
    "ElementSpacing = 1 1 1\nElementType = MET_FLOAT\n";

std::string floats(std::size_t n) {
  std::vector<float> v(n, 40.0f);
  return std::string(reinterpret_cast<const char*>(v.data()), n * sizeof(float));
}

std::string deflated(const std::string& raw) {
  uLongf size = compressBound(raw.size());
  std::string out(size, '\0');
  compress(reinterpret_cast<Bytef*>(out.data()), &size, reinterpret_cast<const Bytef*>(raw.data()), raw.size());
  out.resize(size);
  return out;
}

}  // namespace

TEST(MetaImageVerification, WellFormedFilesPass) {
  test::TempDir tmp;
  const auto mhd = test::write_mhd(tmp.path(), "ok", 3, 3, 3, std::vector<float>(27, 40.0f));
  EXPECT_EQ(verify_metaimage_file(mhd, false), std::vector<fs::path>{tmp / "ok.raw"});
  std::ofstream(tmp / "local.mha", std::ios::binary) << kHeader << "ElementDataFile = LOCAL\n" << floats(27);
  EXPECT_TRUE(verify_metaimage_file(tmp / "local.mha", false).empty());
  const std::string z = deflated(floats(27));
  std::ofstream(tmp / "z.mha", std::ios::binary) << kHeader << "CompressedData = True\nCompressedDataSize = " << z.size()
                                                  << "\nElementDataFile = LOCAL\n" << z;
  EXPECT_NO_THROW(verify_metaimage_file(tmp / "z.mha", false));
  EXPECT_EQ(read_image_file(tmp / "z.mha").voxels[26], 40.0f);
}

// Issue 17: MetaImage read errors (short data, bad compression) were ignored.
TEST(MetaImageVerification, ShortOrDamagedDataIsRefused) {
  test::TempDir tmp;
  std::ofstream(tmp / "short.mha", std::ios::binary) << kHeader << "ElementDataFile = LOCAL\n" << floats(20);
  expect_mha_refused(tmp / "short.mha", "ElementDataFile", "cut short");
  test::write_mhd(tmp.path(), "shortraw", 3, 3, 3, std::vector<float>(26, 40.0f));
  expect_mha_refused(tmp / "shortraw.mhd", "ElementDataFile", "cut short");
  std::string z = deflated(floats(27));
  std::string bad = z;
  bad[z.size() / 2] = static_cast<char>(bad[z.size() / 2] ^ 0x20);
  std::ofstream(tmp / "bad.mha", std::ios::binary) << kHeader << "CompressedData = True\nElementDataFile = LOCAL\n" << bad;
  expect_mha_refused(tmp / "bad.mha", "CompressedData");
  std::ofstream(tmp / "cutz.mha", std::ios::binary) << kHeader << "CompressedData = True\nElementDataFile = LOCAL\n"
                                                     << z.substr(0, z.size() / 2);
  expect_mha_refused(tmp / "cutz.mha", "CompressedData", "cut short");
  std::ofstream(tmp / "size.mha", std::ios::binary) << kHeader << "CompressedData = True\nCompressedDataSize = "
                                                     << z.size() + 100 << "\nElementDataFile = LOCAL\n" << z;
  expect_mha_refused(tmp / "size.mha", "CompressedDataSize");
}

// Issue 17: ElementDataFile could point anywhere on the disk.
TEST(MetaImageVerification, DataFilesMustLieBesideTheHeader) {
  test::TempDir tmp, elsewhere;
  test::write_mhd(elsewhere.path(), "secret", 3, 3, 3, std::vector<float>(27, 40.0f));
  fs::create_directory(tmp / "sub");
  for (const std::string& name :
       {(elsewhere / "secret.raw").string(), std::string("../../") + elsewhere.path().filename().string() + "/secret.raw"}) {
    std::ofstream(tmp / "sub" / "x.mhd") << kHeader << "ElementDataFile = " << name << "\n";
    expect_mha_refused(tmp / "sub" / "x.mhd", "ElementDataFile", "--allow-data-outside");
    EXPECT_NO_THROW(verify_metaimage_file(tmp / "sub" / "x.mhd", true)) << "allowed by the flag";
  }
  fs::create_symlink(elsewhere / "secret.raw", tmp / "sub" / "link.raw");
  std::ofstream(tmp / "sub" / "x.mhd") << kHeader << "ElementDataFile = link.raw\n";
  expect_mha_refused(tmp / "sub" / "x.mhd", "ElementDataFile", "outside");
}

// Issue 17: DimSize 2^32 overflowed the voxel count (segfault); NDims 1,000,000 hung.
TEST(MetaImageVerification, AbsurdHeadersAreRefusedAtOnce) {
  test::TempDir tmp;
  const auto header = [&](const std::string& lines) {
    std::ofstream(tmp / "h.mhd") << "ObjectType = Image\n" << lines << "ElementType = MET_SHORT\nElementDataFile = h.raw\n";
    std::ofstream(tmp / "h.raw") << "xx";
    return tmp / "h.mhd";
  };
  expect_mha_refused(header("NDims = 3\nDimSize = 4294967296 4294967296 4294967296\n"), "DimSize");
  expect_mha_refused(header("NDims = 3\nDimSize = 65537 65536 65536\n"), "DimSize", "2^48");
  expect_mha_refused(header("NDims = 1000000\nDimSize = 1 1 1\n"), "NDims");
  expect_mha_refused(header("NDims = 3\nDimSize = 3 3\n"), "DimSize");
  expect_mha_refused(header("NDims = 3\nDimSize = 3 3 0\n"), "DimSize");
  std::ofstream(tmp / "t.mhd") << kHeader.substr(0, kHeader.find("ElementType")) << "ElementType = MET_FLOAT_ARRAY\nElementDataFile = t.raw\n";
  expect_mha_refused(tmp / "t.mhd", "ElementType");
  std::ofstream(tmp / "p.mhd") << kHeader << "ElementDataFile = slice%s.raw 1 3 1\n";
  expect_mha_refused(tmp / "p.mhd", "ElementDataFile", "%d");
  std::ofstream(tmp / "many.mhd") << kHeader << "ElementDataFile = s%d.raw 0 2000000000 1\n";
  expect_mha_refused(tmp / "many.mhd", "ElementDataFile", "million");
}

// tests/fuzz_regressions/README.md: an ObjectType of 259 characters overflowed MetaIO's char[255] in
// MetaObject::M_Read (glibc's fortify check aborted the fuzzer). Keys and string values that do not fit
// MetaIO's buffers are refused before ITK reads the header, naming the field.
TEST(MetaImageVerification, HeaderValuesLongerThanMetaIOsBuffersAreRefused) {
  test::TempDir tmp;
  const auto finding = tmp / "finding.mha";  // the reader goes by the extension
  fs::copy_file(test::source_dir() / "tests" / "fuzz_regressions" / "fuzz_metaimage" / "crash-a7ee1548", finding);
  expect_mha_refused(finding, "ObjectType", "at most 254");
  EXPECT_THROW(read_image_file(finding), InputError);
  const std::string long_value(255, 'x');
  std::ofstream(tmp / "c.mha") << "Comment = " << long_value << "\n" << kHeader << "ElementDataFile = LOCAL\n" << floats(27);
  expect_mha_refused(tmp / "c.mha", "Comment", "255 characters");
  std::ofstream(tmp / "k.mha") << long_value << " = 1\n" << kHeader << "ElementDataFile = LOCAL\n" << floats(27);
  expect_mha_refused(tmp / "k.mha", "header", "key of 255");
  std::ofstream(tmp / "ok.mha") << "Comment = " << long_value.substr(0, 254) << "\n" << kHeader << "ElementDataFile = LOCAL\n" << floats(27);
  EXPECT_NO_THROW(verify_metaimage_file(tmp / "ok.mha", false)) << "254 characters fit";
}
