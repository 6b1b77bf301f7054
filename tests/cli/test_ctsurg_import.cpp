// ctsurg-import as a user runs it: exit codes, messages that name the file and field, no partial
// output, deterministic files, provenance and sidecar.
#include "ctsurg/core/hdf5_file.h"
#include "ctsurg/core/hu_volume_file.h"
#include "ctsurg/core/provenance.h"
#include "ctsurg/core/file_hash.h"
#include "../preprocess/mhd_writer.h"
#include "../preprocess/nifti_writer.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;
using namespace ctsurg;

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// Runs the importer on bad input: exit 2, the message names `mention`, and `out` holds only what
// was there before.
void expect_rejected(const std::vector<std::string>& args, const std::string& mention, const fs::path& out_folder) {
  const auto before = test::files_in(out_folder);
  const auto r = test::run_tool("ctsurg-import", args);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find(mention), std::string::npos) << "message does not mention '" << mention << "':\n" << r.output;
  EXPECT_EQ(test::files_in(out_folder), before) << "partial output left behind";
}

// A copy of the Philips series of ../shared/data whose slice I150 a test may damage.
fs::path philips_series(const test::TempDir& in) {
  const auto series = in / "series";
  fs::copy(test::shared_data_dir() / "dicom_qa" / "Philips_S21570_S2010", series);
  fs::permissions(series / "I150", fs::perms::owner_write, fs::perm_options::add);
  return series;
}

}  // namespace

TEST(CtsurgImport, HelpAndVersion) {
  auto r = test::run_tool("ctsurg-import", {"--help"});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.output.find("--series"), std::string::npos);
  r = test::run_tool("ctsurg-import", {"--version"});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.output.find("ctsurg"), std::string::npos);
  r = test::run_tool("ctsurg-import", {"only-one-argument"});
  EXPECT_EQ(r.exit_code, 2);
}

TEST(CtsurgImport, BadInputsExitTwoNameTheProblemAndWriteNothing) {
  test::TempDir in, out;
  const auto target = (out / "ct.h5").string();
  expect_rejected({(in / "missing.nii.gz").string(), target}, "missing.nii.gz: does not exist", out.path());
  fs::create_directories(in / "empty");
  std::ofstream(in / "empty" / "notes.txt") << "not dicom";
  expect_rejected({(in / "empty").string(), target}, "no DICOM", out.path());
  std::ofstream(in / "corrupt.nii") << std::string(500, '\x7f');
  expect_rejected({(in / "corrupt.nii").string(), target}, "corrupt.nii: sizeof_hdr", out.path());
  std::vector<float> v(27, 40.0f);
  v[13] = std::nanf("");
  expect_rejected({test::write_mhd(in.path(), "nan", 3, 3, 3, v).string(), target}, "non-finite value", out.path());
  v[13] = 40.0f;
  expect_rejected({test::write_mhd(in.path(), "flat", 3, 3, 3, v, "1 0 1").string(), target}, "spacing", out.path());
  std::ofstream(in / "huge.mhd") << "ObjectType = Image\nNDims = 3\nDimSize = 200000 200000 200000\nElementSpacing = 1 1 "
                                    "1\nElementType = MET_SHORT\nElementDataFile = huge.raw\n";
  expect_rejected({(in / "huge.mhd").string(), target}, "more than 2^48", out.path());
  const auto good = test::write_mhd(in.path(), "good", 3, 3, 3, v);
  expect_rejected({good.string(), (out / "no" / "such" / "ct.h5").string()}, "does not exist", out.path());
  expect_rejected({good.string(), target, "--uneven-slices", "sideways"}, "--uneven-slices", out.path());
}

TEST(CtsurgImport, ExistingOutputSurvivesAFailedRun) {
  test::TempDir in, out;
  std::ofstream(out / "ct.h5") << "precious";
  const auto r = test::run_tool("ctsurg-import", {(in / "missing.nii").string(), (out / "ct.h5").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(slurp(out / "ct.h5"), "precious");
}

TEST(CtsurgImport, WritesHuVolumeWithProvenanceAndSidecarDeterministically) {
  test::TempDir in, out;
  std::vector<float> v(4 * 3 * 2);
  for (std::size_t n = 0; n < v.size(); ++n) v[n] = -1000.0f + 100.0f * float(n);
  const auto src = test::write_mhd(in.path(), "ct", 4, 3, 2, v, "0.5 0.75 2");
  ASSERT_EQ(test::run_tool("ctsurg-import", {src.string(), (out / "a.h5").string()}).exit_code, 0);
  ASSERT_EQ(test::run_tool("ctsurg-import", {src.string(), (out / "b.h5").string(), "-q"}).exit_code, 0);
  ASSERT_TRUE(fs::exists(out / "a.xdmf"));
  EXPECT_NE(slurp(out / "a.xdmf").find("a.h5:/hu/data"), std::string::npos);
  const auto vol = read_hu_volume_file(out / "a.h5");
  EXPECT_EQ(vol.hu.voxels, v);
  EXPECT_NEAR(vol.hu.geometry.spacing[1], 0.75, 1e-12);
  const auto prov = Provenance::read(h5::File::open(out / "a.h5").root());
  EXPECT_EQ(prov["tool"], "ctsurg-import");
  ASSERT_EQ(prov["inputs"].size(), 2u);  // header and raw data file
  EXPECT_EQ(prov["inputs"][0]["sha256"], sha256_file(src));
  // Same input, same content: only the command line (output name) differs between a and b.
  const auto a = read_hu_volume_file(out / "a.h5"), b = read_hu_volume_file(out / "b.h5");
  EXPECT_EQ(a.hu.voxels, b.hu.voxels);
  ASSERT_EQ(test::run_tool("ctsurg-import", {src.string(), (out / "a.h5").string()}).exit_code, 0);
  const std::string first = slurp(out / "a.h5");
  ASSERT_EQ(test::run_tool("ctsurg-import", {src.string(), (out / "a.h5").string()}).exit_code, 0);
  EXPECT_EQ(slurp(out / "a.h5"), first) << "rerun is not byte-identical";
  for (const auto& f : test::files_in(out.path())) EXPECT_EQ(f.filename().string().find(".tmp-"), std::string::npos);
}

TEST(CtsurgImport, MixedSeriesFolderIsRejectedUntilOneIsChosen) {
  CTSURG_REQUIRE_SHARED_DATA();
  test::TempDir in, out;
  const auto qa = test::shared_data_dir() / "dicom_qa";
  fs::create_directories(in / "mixed");
  for (const auto* s : {"GE", "Philips_S21570_S2010"})
    for (const auto& e : fs::directory_iterator(qa / s)) fs::copy(e.path(), in / "mixed" / (std::string(s) + "_" + e.path().filename().string()));
  expect_rejected({(in / "mixed").string(), (out / "ct.h5").string()}, "--series", out.path());
  const auto r = test::run_tool("ctsurg-import", {(in / "mixed").string(), (out / "ct.h5").string(), "--series", "201"});
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

TEST(CtsurgImport, CorruptOrTruncatedDicomSliceIsNamedNotSkipped) {
  CTSURG_REQUIRE_SHARED_DATA();
  test::TempDir in, out;
  const auto series = philips_series(in);
  fs::resize_file(series / "I150", 200000);  // cut off inside the pixel data
  expect_rejected({series.string(), (out / "ct.h5").string()}, "I150: (7FE0,0010): declares 524288 bytes, but the file has", out.path());
  fs::remove(series / "I150");
  fs::copy(test::shared_data_dir() / "dicom_qa" / "Philips_S21570_S2010" / "I150", series / "I150");
  fs::permissions(series / "I150", fs::perms::owner_write, fs::perm_options::add);
  {
    std::fstream f(series / "I150", std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(200);
    const std::string noise(400, '\xa5');  // garbage inside the header, after the DICM marker
    f.write(noise.data(), static_cast<std::streamsize>(noise.size()));
  }
  expect_rejected({series.string(), (out / "ct.h5").string()}, "I150: (A5A5,A5A5): '\\xa5\\xa5' is not a DICOM value representation", out.path());
}

TEST(CtsurgImport, MissingSliceIsReported) {
  CTSURG_REQUIRE_SHARED_DATA();
  test::TempDir in, out;
  const auto series = in / "series";
  fs::copy(test::shared_data_dir() / "dicom_qa" / "Philips_S21570_S2010", series);
  // I150 is a middle slice of the 28 (5 mm apart): removing it leaves one 10 mm gap.
  fs::remove(series / "I150");
  const auto r = test::run_tool("ctsurg-import", {series.string(), (out / "ct.h5").string()});
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("about 1 slice(s) appear to be missing"), std::string::npos) << r.output;
}

TEST(CtsurgImport, TiltAndUnevenSpacingAreWarnedWithNumbers) {
  CTSURG_REQUIRE_SHARED_DATA();
  test::TempDir out;
  const auto r = test::run_tool("ctsurg-import", {(test::shared_data_dir() / "dicom_qa" / "GE").string(), (out / "ge.h5").string()});
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("gantry tilt of 18.5"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("uneven slice spacing: gaps from 1.14"), std::string::npos) << r.output;
}

// Issue 17: damaged NIfTI files imported silently (a cut file as zeros, a bad gzip CRC, NaN voxels
// as 0 HU, pixdim 0 as 1 mm, a NaN qform mirrored, a broken magic as Analyze, a bad vox_offset), a
// NaN sform crashed and an srow of -1.7e38 hung. Each is refused (exit 2) naming the field.
TEST(CtsurgImport, DamagedNiftiFilesAreRefused) {
  test::TempDir in, out;
  const auto target = (out / "ct.h5").string();
  test::NiftiSpec big;
  big.dim = {3, 20, 20, 20, 1, 1, 1, 1};
  const std::string good = test::nifti_bytes(big);
  test::write_nifti_bytes(in / "cut.nii.gz", good.substr(0, good.size() / 2));
  expect_rejected({(in / "cut.nii.gz").string(), target}, "cut.nii.gz: voxel data: the file is cut short", out.path());
  test::write_nifti_bytes(in / "crc.nii.gz", good);
  {
    std::string gz = test::read_bytes(in / "crc.nii.gz");
    gz[gz.size() - 6] = static_cast<char>(gz[gz.size() - 6] ^ 1);  // the stored CRC-32
    std::ofstream(in / "crc.nii.gz", std::ios::binary) << gz;
  }
  expect_rejected({(in / "crc.nii.gz").string(), target}, "crc.nii.gz: gzip:", out.path());
  const auto broken = [&](const char* name, auto change, const std::string& mention) {
    test::NiftiSpec s;
    change(s);
    test::write_nifti(in / name, s);
    expect_rejected({(in / name).string(), target}, mention, out.path());
  };
  broken("nan.nii", [](test::NiftiSpec& s) { s.values.assign(24, 0.0f), s.values[7] = std::nanf(""); }, "non-finite");
  broken("pixdim.nii", [](test::NiftiSpec& s) { s.pixdim[1] = 0.0f; }, "pixdim[1]");
  broken("qform.nii", [](test::NiftiSpec& s) { s.qform_code = 1, s.quatern[0] = std::nanf(""); }, "quatern_b/c/d");
  broken("sform.nii", [](test::NiftiSpec& s) { s.srow[0] = std::nanf(""); }, "srow_x");
  broken("srow.nii", [](test::NiftiSpec& s) { s.srow[0] = -1.7e38f; }, "srow_x");
  broken("magic.nii", [](test::NiftiSpec& s) { s.magic = std::string("ab1\0", 4); }, "magic");
  broken("offset.nii", [](test::NiftiSpec& s) { s.vox_offset = 340; }, "vox_offset");
}

// Issue 17: MetaImage read errors were ignored, ElementDataFile could name any file, DimSize 2^32
// crashed and NDims 1,000,000 hung.
TEST(CtsurgImport, DamagedMetaImageFilesAreRefused) {
  test::TempDir in, out, elsewhere;
  const auto target = (out / "ct.h5").string();
  test::write_mhd(in.path(), "short", 3, 3, 3, std::vector<float>(20, 40.0f));
  expect_rejected({(in / "short.mhd").string(), target}, "short.mhd: ElementDataFile: the voxel data are cut short", out.path());
  test::write_mhd(elsewhere.path(), "data", 3, 3, 3, std::vector<float>(27, 40.0f));
  std::ofstream(in / "far.mhd") << "ObjectType = Image\nNDims = 3\nDimSize = 3 3 3\nElementType = MET_FLOAT\n"
                                << "ElementDataFile = " << (elsewhere / "data.raw").string() << "\n";
  expect_rejected({(in / "far.mhd").string(), target}, "--allow-data-outside", out.path());
  const auto r = test::run_tool("ctsurg-import", {(in / "far.mhd").string(), target, "--allow-data-outside"});
  EXPECT_EQ(r.exit_code, 0) << r.output;
  fs::remove(out / "ct.h5");
  fs::remove(out / "ct.xdmf");
  std::ofstream(in / "big.mhd") << "NDims = 3\nDimSize = 4294967296 4294967296 4294967296\nElementType = MET_SHORT\n"
                                << "ElementDataFile = big.raw\n";
  std::ofstream(in / "big.raw") << "xx";
  expect_rejected({(in / "big.mhd").string(), target}, "big.mhd: DimSize", out.path());
  std::ofstream(in / "ndims.mhd") << "NDims = 1000000\nDimSize = 3 3 3\nElementType = MET_SHORT\nElementDataFile = big.raw\n";
  expect_rejected({(in / "ndims.mhd").string(), target}, "ndims.mhd: NDims", out.path());
}

// Issue 17: --rescale-slope 1e300 wrote an all-infinite volume.
TEST(CtsurgImport, ARescaleBeyondFloatRangeIsRefused) {
  test::TempDir in, out;
  const auto src = test::write_mhd(in.path(), "ct", 3, 3, 3, std::vector<float>(27, 40.0f));
  expect_rejected({src.string(), (out / "ct.h5").string(), "--rescale-slope", "1e300"}, "--rescale-slope", out.path());
}

// Issue 17: `ctsurg-import c.nii.gz c.nii.gz` replaced the CT with HDF5, and any output suffix was
// accepted. The output is an .h5 file that is none of the inputs.
TEST(CtsurgImport, TheOutputIsAnH5FileThatIsNotAnInput) {
  test::TempDir in;
  const auto ct = test::write_nifti(in / "c.nii.gz", {});
  const std::string before = test::read_bytes(ct);
  for (const auto& output : {ct, in / "c.nii", in / "out.mha"}) {
    const auto r = test::run_tool("ctsurg-import", {ct.string(), output.string()});
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("suffix"), std::string::npos) << r.output;
  }
  EXPECT_EQ(test::read_bytes(ct), before) << "the input was replaced";
  const auto src = test::write_mhd(in.path(), "ct", 3, 3, 3, std::vector<float>(27, 40.0f));
  fs::create_symlink(in / "ct.raw", in / "raw.h5");
  const auto r = test::run_tool("ctsurg-import", {src.string(), (in / "raw.h5").string()});
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("is the input"), std::string::npos) << r.output;
}

// Issue 17: on a full disk (here a file-size limit, SIGXFSZ ignored as Python does for its
// children), an unreadable .h5 was renamed into place over the previous one, exit 0, and the
// writer crashed at exit after the error. Now: exit 1, the previous file untouched.
TEST(CtsurgImport, AFullDiskKeepsThePreviousOutput) {
  test::TempDir in, out;
  std::vector<float> v(64 * 64 * 32);
  for (std::size_t n = 0; n < v.size(); ++n) v[n] = static_cast<float>((n * 2654435761u) % 3000) - 1000.0f;
  const auto src = test::write_mhd(in.path(), "ct", 64, 64, 32, v);
  std::ofstream(out / "ct.h5") << "previous";
  for (const int kib : {4, 100, 180}) {
    const auto r = test::run_shell("trap '' XFSZ; ulimit -f " + std::to_string(kib) + "; CTSURG_NO_PROGRESS=1 " +
                                   std::string(CTSURG_TOOL_DIR) + "/ctsurg-import " + src.string() + " " +
                                   (out / "ct.h5").string());
    EXPECT_EQ(r.exit_code, 1) << "limit " << kib << " KiB: " << r.output;
    EXPECT_NE(r.output.find("ct.h5"), std::string::npos) << r.output;
    EXPECT_EQ(slurp(out / "ct.h5"), "previous") << "limit " << kib << " KiB";
    EXPECT_EQ(test::files_in(out.path()).size(), 1u) << "temporary files left behind";
  }
}

// Issue 17: CTSURG_MAX_MEMORY_MB=50 did not cap real use (197 MB import), bad values were ignored
// and refusals exited 2 where docs/formats.md says 1.
TEST(CtsurgImport, TheMemoryCapIsValidatedAndHolds) {
  test::TempDir out;
  const auto ct = test::source_dir() / "data_samples" / "heart" / "heart_ct.nii.gz";
  const std::string tool = std::string(CTSURG_TOOL_DIR) + "/ctsurg-import ";
  for (const char* bad : {"fifty", "0", "-1"}) {
    const auto r = test::run_shell(std::string("CTSURG_MAX_MEMORY_MB=") + bad + " " + tool + ct.string() + " " +
                                   (out / "ct.h5").string());
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("CTSURG_MAX_MEMORY_MB"), std::string::npos) << r.output;
  }
  // Under any cap the import either fits (exit 0) or stops as out of memory (exit 1) naming the cap:
  // never bad input, never a crash in a library that met the limit.
  int refused = 0;
  for (int mb = 8; mb <= 64; mb += 4) {
    const std::string cap = "CTSURG_MAX_MEMORY_MB=" + std::to_string(mb);
    const auto r = test::run_shell(cap + " " + tool + ct.string() + " " + (out / "ct.h5").string());
    EXPECT_TRUE(r.exit_code == 0 || r.exit_code == 1) << cap << ": exit " << r.exit_code << "\n" << r.output;
    if (r.exit_code == 1) {
      ++refused;
      EXPECT_NE(r.output.find(cap), std::string::npos) << r.output;
      EXPECT_TRUE(test::files_in(out.path()).empty());
    }
  }
  EXPECT_GT(refused, 0) << "no cap was too small: the test does not test the cap";
  const auto ok = test::run_shell("CTSURG_MAX_MEMORY_MB=2000 " + tool + ct.string() + " " + (out / "ct.h5").string());
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
}

// Issue 17: library noise was printed before ctsurg's error, and errors named a temporary copy of a
// repaired NRRD header instead of the user's file.
TEST(CtsurgImport, OneMessageNamingTheUsersFile) {
  test::TempDir in, out;
  test::write_nifti_bytes(in / "noisy.nii", test::nifti_bytes({}).substr(0, 300));
  auto r = test::run_tool("ctsurg-import", {(in / "noisy.nii").string(), (out / "ct.h5").string()});
  EXPECT_EQ(r.exit_code, 2);
  std::istringstream lines(r.output);
  for (std::string line; std::getline(lines, line);) {
    EXPECT_EQ(line.rfind("ctsurg-import: ", 0), 0u) << "a line that is not ctsurg's: " << line;
  }
  std::ofstream(in / "scan.nhdr") << "NRRD0004\ntype: short\ndimension: 3\nspace: left-posterior-superior\n"
                                  << "sizes: 4 4 4\nspacings: 1 1 1\nencoding: raw\nendian: little\n"
                                  << "data file: scan.raw\n";
  std::ofstream(in / "scan.raw") << std::string(20, '\0');  // 128 bytes needed
  r = test::run_tool("ctsurg-import", {(in / "scan.nhdr").string(), (out / "ct.h5").string()});
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find((in / "scan.nhdr").string()), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("ctsurg-nrrd-"), std::string::npos) << "names the temporary copy: " << r.output;
}

// Issue 17: a DICOM slice whose BitsAllocated lies (says 32 over 16-bit pixel data) crashed the
// decoder. Refused naming the slice and the field.
TEST(CtsurgImport, ADicomSliceWhoseBitsAllocatedLiesIsRefused) {
  CTSURG_REQUIRE_SHARED_DATA();
  test::TempDir in, out;
  const auto series = philips_series(in);
  std::string bytes = test::read_bytes(series / "I150");
  const std::string tag("\x28\x00\x00\x01US\x02\x00", 8);  // (0028,0100) US, length 2, explicit VR little endian
  const auto at = bytes.find(tag);
  ASSERT_NE(at, std::string::npos);
  ASSERT_EQ(bytes[at + 8], '\x10');  // 16
  bytes[at + 8] = '\x20';            // 32
  std::ofstream(series / "I150", std::ios::binary) << bytes;
  expect_rejected({series.string(), (out / "ct.h5").string()}, "I150: BitsAllocated (0028,0100)", out.path());
}
