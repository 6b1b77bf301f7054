#include "ctsurg/core/provenance.h"

#include "ctsurg/core/file_hash.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <fstream>

using namespace ctsurg;

TEST(FileHash, Sha256OfKnownContent) {
  test::TempDir tmp;
  std::ofstream(tmp / "abc") << "abc";
  EXPECT_EQ(sha256_file(tmp / "abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_THROW(sha256_file(tmp / "missing"), std::exception);
}

TEST(Provenance, RecordsInputsAndChainsUpstreamFiles) {
  test::TempDir tmp;
  std::ofstream(tmp / "ct.nii") << "pretend ct";
  Provenance first{"ctsurg-import", "1", {"ctsurg-import", "ct.nii", "a.h5"}, {}, nlohmann::json::array()};
  first.add_input(tmp / "ct.nii");
  {
    auto f = h5::File::create(tmp / "a.h5");
    auto root = f.root();
    first.write(root);
    f.close();
  }
  Provenance second{"ctsurg-grid", "1", {"ctsurg-grid", "a.h5", "b.h5"}, {}, nlohmann::json::array()};
  second.add_input(tmp / "a.h5");
  {
    auto f = h5::File::create(tmp / "b.h5");
    auto root = f.root();
    second.write(root);
    f.close();
  }
  const auto j = Provenance::read(h5::File::open(tmp / "b.h5").root());
  EXPECT_EQ(j["tool"], "ctsurg-grid");
  EXPECT_EQ(j["command_line"][1], "a.h5");
  EXPECT_EQ(j["inputs"][0]["sha256"], sha256_file(tmp / "a.h5"));
  ASSERT_EQ(j["upstream"].size(), 1u);
  EXPECT_EQ(j["upstream"][0]["tool"], "ctsurg-import");
  EXPECT_EQ(j["upstream"][0]["inputs"][0]["sha256"], sha256_file(tmp / "ct.nii"));
}
