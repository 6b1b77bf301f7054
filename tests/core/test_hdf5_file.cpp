#include "ctsurg/core/hdf5_file.h"

#include "ctsurg/core/error.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <fstream>

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
  { auto f = h5::File::create(tmp / "x.h5"); f.root().create_group("g"); }
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
  }
  const auto slurp = [](const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  EXPECT_EQ(slurp(tmp / "a.h5"), slurp(tmp / "b.h5"));
}
