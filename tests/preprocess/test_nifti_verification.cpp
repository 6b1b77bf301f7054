// What ctsurg verifies in NIfTI files before ITK reads them (nifti_verification.h). Each defect of
// issue 17 that ITK's NIfTI library repaired silently is reproduced on a hand-made file and must be
// refused with the field that has it; the bundled heart and well-formed files pass.
#include "ctsurg/preprocess/nifti_verification.h"

#include "ctsurg/core/error.h"
#include "ctsurg/preprocess/image_file_reader.h"
#include "nifti_writer.h"
#include "reader_refusal.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>

namespace fs = std::filesystem;
using namespace ctsurg;

namespace {

void expect_nifti_refused(const fs::path& path, const std::string& field, const std::string& mention = "") {
  test::expect_refused(path, [](const fs::path& p) { verify_nifti_file(p); }, field, mention);
}

}  // namespace

TEST(NiftiVerification, WellFormedFilesPass) {
  test::TempDir tmp;
  for (const char* name : {"ok.nii", "ok.nii.gz"}) {
    const auto path = test::write_nifti(tmp / name, {});
    std::vector<std::string> warnings;
    EXPECT_NO_THROW(verify_nifti_file(path, &warnings)) << name;
    EXPECT_TRUE(warnings.empty());
    const Volume<float> v = read_image_file(path);
    EXPECT_EQ(v.voxels[5], 5.0f);
  }
  const fs::path heart = test::source_dir() / "data_samples" / "heart";
  EXPECT_NO_THROW(verify_nifti_file(heart / "heart_ct.nii.gz"));
  EXPECT_NO_THROW(verify_nifti_file(heart / "heart_mask.nii.gz"));
}

// Issue 17: a NIfTI cut at 50 % imported with half its voxels 0 HU.
TEST(NiftiVerification, ACutFileIsRefused) {
  test::TempDir tmp;
  const std::string bytes = test::nifti_bytes({});
  for (const char* name : {"cut.nii", "cut.nii.gz"}) {
    test::write_nifti_bytes(tmp / name, bytes.substr(0, 352 + (bytes.size() - 352) / 2));
    expect_nifti_refused(tmp / name, "voxel data", "cut short");
    test::write_nifti_bytes(tmp / name, bytes.substr(0, 200));
    expect_nifti_refused(tmp / name, "header");
  }
}

// Issue 17: a .nii.gz with a wrong gzip CRC (one flipped bit) imported with changed voxels.
TEST(NiftiVerification, AGzipCrcOrLengthMismatchIsRefused) {
  test::TempDir tmp;
  test::write_nifti(tmp / "good.nii.gz", {});
  const std::string gz = test::read_bytes(tmp / "good.nii.gz");
  for (const std::size_t from_end : {8u, 5u, 4u, 1u}) {  // bytes of the CRC-32, then of ISIZE
    std::string bad = gz;
    bad[bad.size() - from_end] = static_cast<char>(bad[bad.size() - from_end] ^ 0x01);
    { std::ofstream(tmp / "bad.nii.gz", std::ios::binary) << bad; }
    expect_nifti_refused(tmp / "bad.nii.gz", "gzip");
  }
  // A flipped bit in the compressed data: refused (a decode error or a CRC mismatch), or, where the
  // bit does not change the decoded bytes (a code length of an unused symbol), the same image.
  const std::vector<float> original = read_image_file(tmp / "good.nii.gz").voxels;
  int refused = 0, flips = 0;
  for (std::size_t at = 10; at + 8 < gz.size(); ++at, ++flips) {
    std::string bad = gz;
    bad[at] = static_cast<char>(bad[at] ^ 0x04);
    { std::ofstream(tmp / "flip.nii.gz", std::ios::binary) << bad; }
    try {
      EXPECT_EQ(read_image_file(tmp / "flip.nii.gz").voxels, original) << "bit flipped at byte " << at;
    } catch (const InputError&) {
      ++refused;
    }
  }
  EXPECT_GT(refused, flips / 2);
}

// Issue 17: NaN/Inf voxels became 0 HU inside the NIfTI library, before ctsurg's finite check.
TEST(NiftiVerification, NonFiniteVoxelsAreRefusedByPosition) {
  test::TempDir tmp;
  for (const float bad : {std::nanf(""), std::numeric_limits<float>::infinity()}) {
    test::NiftiSpec s;
    s.values.assign(24, 1.0f);
    s.values[1 + 4 * (2 + 3 * 1)] = bad;  // voxel (1, 2, 1)
    test::write_nifti(tmp / "nan.nii.gz", s);
    expect_nifti_refused(tmp / "nan.nii.gz", "voxel data", "(1, 2, 1)");
  }
}

// Issue 17: pixdim 0/NaN became 1 mm; a NaN qform flipped left and right; a NaN sform crashed; an
// srow of -1.7e38 hung; a broken magic was read as Analyze; a bad vox_offset read the wrong bytes.
TEST(NiftiVerification, BrokenHeaderFieldsAreRefusedByName) {
  test::TempDir tmp;
  const auto refused = [&](const test::NiftiSpec& s, const std::string& field) {
    expect_nifti_refused(test::write_nifti(tmp / "h.nii", s), field);
  };
  for (const float v : {0.0f, -1.5f, std::nanf("")}) {
    test::NiftiSpec s;
    s.pixdim[2] = v;
    refused(s, "pixdim[2]");
  }
  test::NiftiSpec q;
  q.qform_code = 1;
  q.quatern[1] = std::nanf("");
  refused(q, "quatern");
  q.quatern = {0.9f, 0.9f, 0, 0, 0, 0};
  refused(q, "quatern");
  test::NiftiSpec f;
  f.srow[5] = std::nanf("");
  refused(f, "srow_y");
  f.srow[5] = -1.7e38f;
  refused(f, "srow_y");
  f.srow = {1, 0, 0, 0, 2, 0, 0, 0, 0, 0, 0, 0};
  refused(f, "srow");  // singular
  test::NiftiSpec m;
  m.magic = std::string("n+2\0", 4);
  refused(m, "magic");
  m.magic = std::string("\0\0\0\0", 4);
  refused(m, "magic");
  m.magic = std::string("ni1\0", 4);
  refused(m, "magic");
  for (const float offset : {348.0f, 352.5f, 368.0f, 1e9f, std::nanf("")}) {
    test::NiftiSpec o;
    o.vox_offset = offset;
    const std::string bytes = test::nifti_bytes(o);
    test::write_nifti_bytes(tmp / "o.nii", offset == 368.0f ? bytes.substr(0, bytes.size() - 16) : bytes);
    EXPECT_THROW(verify_nifti_file(tmp / "o.nii"), InputError) << "vox_offset " << offset;
  }
  test::NiftiSpec d;
  d.dim = {3, 30000, 30000, 30000, 1, 1, 1, 1};
  d.values = {0};
  refused(d, "voxel data");  // 108 TB of data in a tiny file: cut short, never allocated
  d.dim = {4, 4, 3, 2, 5, 1, 1, 1};
  d.values.clear();
  refused(d, "dim[4]");
  test::NiftiSpec t;
  t.datatype = 32;  // complex64
  refused(t, "datatype");
  t.datatype = 16;
  t.bitpix = 16;
  refused(t, "bitpix");
  test::NiftiSpec sl;
  sl.scl_slope = std::nanf("");
  refused(sl, "scl_slope");
}
