#include "ctsurg/core/hdf5_file.h"

#include "ctsurg/core/error.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <fstream>
#include <sstream>

using namespace ctsurg;

TEST(Hdf5File, DatasetsAndAttributesRoundTripWithTypeConversion) {
  test::TempDir tmp;
  const auto path = tmp / "x.h5";
  {
    auto f = h5::File::create(path);
    auto root = f.root();
    auto g = root.create_group("g");
    std::vector<int16_t> data(10 * 20 * 30);
    for (std::size_t n = 0; n < data.size(); ++n) data[n] = static_cast<int16_t>(int(n % 4000) - 2000);
    const std::array<uint64_t, 3> shape{10, 20, 30};
    g.write_dataset<int16_t>("d", data, shape);
    g.set_attribute("s", std::string("hello"));
    g.set_attribute("x", 2.5);
    g.set_attribute("n", int64_t{7});
    const std::array<double, 3> v{1, 2, 3};
    g.set_attribute("v", std::span<const double>(v));
    f.close();
  }
  const auto f = h5::File::open(path);
  const auto g = f.root().open_group("g");
  std::vector<uint64_t> shape;
  const auto as_float = g.read_dataset<float>("d", &shape);
  EXPECT_EQ(shape, (std::vector<uint64_t>{10, 20, 30}));
  EXPECT_EQ(as_float[4001], float(4001 % 4000 - 2000));
  EXPECT_EQ(g.dataset_type_name("d"), "int16");
  EXPECT_EQ(g.string_attribute("s"), "hello");
  EXPECT_EQ(g.double_attribute("x"), 2.5);
  EXPECT_EQ(g.int_attribute("n"), 7);
  EXPECT_EQ(g.doubles_attribute("v"), (std::vector<double>{1, 2, 3}));
}

TEST(Hdf5File, MissingThingsAreInputErrorsNamingFileAndObject) {
  test::TempDir tmp;
  {
    auto f = h5::File::create(tmp / "x.h5");
    f.root().create_group("g");
    f.close();
  }
  const auto f = h5::File::open(tmp / "x.h5");
  try {
    f.root().open_group("g").read_dataset<float>("nope");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "/g/nope");
    EXPECT_NE(e.file().find("x.h5"), std::string::npos);
  }
  EXPECT_THROW(f.root().open_group("absent"), InputError);
  EXPECT_THROW(f.root().string_attribute("absent"), InputError);
  std::ofstream(tmp / "text.h5") << "not hdf5";
  EXPECT_THROW(h5::File::open(tmp / "text.h5"), InputError);
  EXPECT_THROW(h5::File::open(tmp / "missing.h5"), InputError);
}

TEST(Hdf5File, SameContentGivesByteIdenticalFiles) {
  test::TempDir tmp;
  for (const char* name : {"a.h5", "b.h5"}) {
    auto f = h5::File::create(tmp / name);
    auto g = f.root().create_group("g");
    std::vector<float> d(5000, 1.5f);
    const std::array<uint64_t, 1> shape{5000};
    g.write_dataset<float>("d", d, shape);
    g.set_attribute("s", std::string("x"));
    f.close();
  }
  const auto slurp = [](const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  EXPECT_EQ(slurp(tmp / "a.h5"), slurp(tmp / "b.h5"));
}

namespace {

// A small file with the kinds of object ctsurg files hold: compressed and small datasets, numeric
// and string attributes, nested groups.
void write_sample(const std::filesystem::path& path) {
  auto f = h5::File::create(path);
  auto root = f.root();
  root.set_attribute("ctsurg_format", std::string("sample"));
  auto g = root.create_group("g");
  std::vector<float> big(3000);
  for (std::size_t n = 0; n < big.size(); ++n) big[n] = 0.25f * static_cast<float>(n);
  g.write_dataset<float>("big", big, std::array<uint64_t, 2>{1000, 3});
  g.write_dataset<int32_t>("small", std::vector<int32_t>{1, 2, 3}, std::array<uint64_t, 1>{3});
  const std::array<double, 3> v{1, 2, 3};
  g.set_attribute("v", std::span<const double>(v));
  g.set_attribute("s", std::string("hello"));
  f.close();
}

// Everything write_sample() wrote, read back; InputError when the file is refused.
std::string read_sample(const std::filesystem::path& path) {
  const auto f = h5::File::open(path);
  const auto root = f.root();
  const auto g = root.open_group("g");
  std::ostringstream s;
  s << root.string_attribute("ctsurg_format") << g.string_attribute("s");
  for (const float x : g.read_dataset<float>("big")) s << x << ',';
  for (const int32_t x : g.read_dataset<int32_t>("small")) s << x << ',';
  for (const double x : g.doubles_attribute("v")) s << x << ',';
  return s.str();
}

}  // namespace

// Issue 17: a corrupted HDF5 file crashed libhdf5 or read as different values. Every byte of a
// file flipped in turn: the file is refused (InputError) or reads back exactly, never anything
// else; cut anywhere, it is refused.
TEST(Hdf5File, AFlippedBitOrACutFileIsRefusedNeverMisread) {
  test::TempDir tmp;
  write_sample(tmp / "good.h5");
  const std::string expected = read_sample(tmp / "good.h5");
  const std::string bytes = test::read_bytes(tmp / "good.h5");
  ASSERT_GT(bytes.size(), 1000u);
  int refused = 0;
  for (std::size_t at = 0; at < bytes.size(); ++at) {
    std::string bad = bytes;
    bad[at] = static_cast<char>(bad[at] ^ 0x10);
    { std::ofstream(tmp / "bad.h5", std::ios::binary) << bad; }
    try {
      EXPECT_EQ(read_sample(tmp / "bad.h5"), expected) << "byte " << at << " flipped reads as different content";
    } catch (const InputError&) {
      ++refused;
    }
  }
  EXPECT_GT(refused, static_cast<int>(bytes.size() / 2));
  for (const std::size_t keep : {std::size_t{0}, std::size_t{8}, std::size_t{100}, bytes.size() / 2, bytes.size() - 1}) {
    { std::ofstream(tmp / "cut.h5", std::ios::binary) << bytes.substr(0, keep); }
    EXPECT_THROW(read_sample(tmp / "cut.h5"), InputError) << "cut at " << keep;
  }
}

// Files without checksums (HDF5 superblock version 0: any other writer's default) cannot be
// verified and are refused by name.
TEST(Hdf5File, FilesWithoutChecksumsAreRefused) {
  test::TempDir tmp;
  const hid_t f = H5Fcreate((tmp / "old.h5").c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  H5Fclose(f);
  try {
    h5::File::open(tmp / "old.h5");
    ADD_FAILURE() << "a superblock-0 file was opened";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "superblock");
  }
}

// Issue 17: HDF5 flush and close errors were ignored (an unreadable .h5 was renamed into place) and
// the writer crashed at exit after a disk-full error. In a child limited to 4 KiB per file (SIGXFSZ
// ignored, as the tools do), close() reports the failure and the process exits cleanly.
TEST(Hdf5File, AFailedWriteIsReportedAndTheProcessExitsCleanly) {
  test::TempDir tmp;
  const pid_t pid = fork();
  if (pid == 0) {
    std::signal(SIGXFSZ, SIG_IGN);
    rlimit limit{4096, 4096};
    setrlimit(RLIMIT_FSIZE, &limit);
    int code = 3;
    try {
      write_sample(tmp / "big.h5");
      code = 1;  // no error
    } catch (const RuntimeError& e) {
      code = std::string(e.what()).find("big.h5") != std::string::npos ? 0 : 2;
    }
    std::exit(code);  // runs HDF5's atexit clean-up, where the crash was
  }
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status)) << "the writer crashed (signal " << WTERMSIG(status) << ")";
  EXPECT_EQ(WEXITSTATUS(status), 0) << "1: no error reported; 2: the message does not name the file";
}
