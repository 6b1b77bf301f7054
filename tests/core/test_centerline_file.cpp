// Tests for core/include/ctsurg/core/centerline_file.h: round trip of every array and attribute, the
// VTK sidecar, byte-identical rewrites, and refusals on write and read naming the object.
#include "ctsurg/core/centerline_file.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/hdf5_file.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <functional>

namespace fs = std::filesystem;
using ctsurg::test::TempDir;
using ctsurg::test::test_provenance;

namespace {

// A Y: branch 0 from end node 0 to junction 1, branches 1 and 2 from the junction to end nodes 2 and 3.
ctsurg::Centerline y_centerline() {
  ctsurg::Centerline c;
  c.nodes = {0, 0, 0, 10, 0, 0, 20, 5, 0, 20, -5, 1};
  c.points = {0, 0, 0, 5, 0.1, 0, 10, 0, 0,           //
              10, 0, 0, 15, 2.5, 0, 20, 5, 0,         //
              10, 0, 0, 15, -2.5, 0.5, 20, -5, 1};
  c.radius = {3, 3.1, 3.2, 3.2, 2.5, 2.4, 3.2, 2.2, 2.0};
  c.branch_offsets = {0, 3, 6, 9};
  c.branch_nodes = {0, 1, 1, 2, 1, 3};
  c.label = 52;
  c.source_spacing_mm = {0.8, 0.8, 1.5};
  c.parameters = R"({"spur_length_factor":2})";
  return c;
}

TEST(CenterlineFile, RoundTrip) {
  TempDir dir;
  const auto c = y_centerline();
  ctsurg::write_centerline_file(dir / "c.h5", c, test_provenance());
  const auto r = ctsurg::read_centerline_file(dir / "c.h5");
  EXPECT_EQ(r.points, c.points);
  EXPECT_EQ(r.radius, c.radius);
  EXPECT_EQ(r.branch_offsets, c.branch_offsets);
  EXPECT_EQ(r.branch_nodes, c.branch_nodes);
  EXPECT_EQ(r.nodes, c.nodes);
  EXPECT_EQ(r.label, 52);
  EXPECT_EQ(r.source_spacing_mm, c.source_spacing_mm);
  EXPECT_EQ(r.parameters, c.parameters);
  EXPECT_EQ(r.branch_count(), 3);
  const std::string vtk = ctsurg::test::read_bytes(dir / "c.vtk");
  EXPECT_EQ(vtk.rfind("# vtk DataFile Version 3.0\n", 0), 0u);
  EXPECT_NE(vtk.find("DATASET POLYDATA\nPOINTS 9 double\n"), std::string::npos);
  EXPECT_NE(vtk.find("LINES 3 12\n3 0 1 2\n3 3 4 5\n3 6 7 8\n"), std::string::npos) << vtk;
  EXPECT_NE(vtk.find("POINT_DATA 9\nSCALARS radius double 1\nLOOKUP_TABLE default\n3\n3.1\n"), std::string::npos);
  const auto f = ctsurg::h5::File::open(dir / "c.h5");
  EXPECT_EQ(f.root().string_attribute("ctsurg_format"), "centerline");
  EXPECT_EQ(f.root().open_group("centerline").string_attribute("frame"), "LPS");
  // Same content, same bytes.
  const std::string first = ctsurg::test::read_bytes(dir / "c.h5");
  ctsurg::write_centerline_file(dir / "c.h5", c, test_provenance());
  EXPECT_EQ(ctsurg::test::read_bytes(dir / "c.h5"), first);
}

void expect_refused(const std::function<void(ctsurg::Centerline&)>& change, const std::string& field) {
  auto c = y_centerline();
  change(c);
  try {
    ctsurg::validate_centerline(c, "c.h5");
    ADD_FAILURE() << "not refused: " << field;
  } catch (const ctsurg::InputError& e) {
    EXPECT_EQ(e.file(), "c.h5");
    EXPECT_EQ(e.field(), field) << e.what();
  }
}

TEST(CenterlineFile, ValidationNamesTheField) {
  expect_refused([](auto& c) { c.branch_offsets.clear(); c.branch_nodes.clear(); }, "/centerline/branch_offsets");
  expect_refused([](auto& c) { c.radius.pop_back(); }, "/centerline/radius");
  expect_refused([](auto& c) { c.radius[4] = 0.0; }, "/centerline/radius");
  expect_refused([](auto& c) { c.radius[4] = std::nan(""); }, "/centerline/radius");
  expect_refused([](auto& c) { c.points[7] = std::numeric_limits<double>::infinity(); }, "/centerline/points");
  expect_refused([](auto& c) { c.points.push_back(1.0); }, "/centerline/points");
  expect_refused([](auto& c) { c.branch_offsets = {0, 1, 6, 9}; }, "/centerline/branch_offsets");
  expect_refused([](auto& c) { c.branch_offsets.back() = 8; }, "/centerline/branch_offsets");
  expect_refused([](auto& c) { c.branch_nodes[5] = 4; }, "/centerline/branch_nodes");
  expect_refused([](auto& c) { c.branch_nodes.pop_back(); }, "/centerline/branch_nodes");
  expect_refused([](auto& c) { c.points[0] = 0.5; }, "/centerline/branch_nodes");  // first point off its node
  expect_refused([](auto& c) { c.nodes.insert(c.nodes.end(), {1, 2, 3}); }, "/centerline/nodes");  // ends no branch
  expect_refused([](auto& c) { c.nodes[2] = std::nan(""); }, "/centerline/nodes");
  expect_refused([](auto& c) { c.source_spacing_mm[1] = -1.0; }, "/centerline/source_spacing_mm");
}

TEST(CenterlineFile, WriteRefusesInvalidAndLeavesNothing) {
  TempDir dir;
  auto c = y_centerline();
  c.radius[0] = -1.0;
  EXPECT_THROW(ctsurg::write_centerline_file(dir / "c.h5", c, test_provenance()), ctsurg::InputError);
  EXPECT_TRUE(ctsurg::test::files_in(dir.path()).empty());
}

// A file whose datasets are written by hand, to check what the reader refuses.
void write_raw(const fs::path& path, const std::function<void(ctsurg::h5::Group&)>& change) {
  const auto c = y_centerline();
  auto f = ctsurg::h5::File::create(path);
  {
    auto root = f.root();
    root.set_attribute("ctsurg_format", std::string("centerline"));
    root.set_attribute("ctsurg_format_version", int64_t{1});
    auto s = root.create_group("centerline");
    change(s);
    const auto set = [&](const char* name, auto value) {
      if (!s.has_attribute(name)) s.set_attribute(name, value);
    };
    set("frame", std::string("LPS"));
    set("units", std::string("mm"));
    set("points", int64_t{9});
    set("branches", int64_t{3});
    set("nodes", int64_t{4});
    set("label", int64_t{52});
    set("source_spacing_mm", std::span<const double>(c.source_spacing_mm));
    set("parameters", std::string("{}"));
    const std::array<uint64_t, 2> p3{9, 3}, b2{3, 2}, n3{4, 3};
    const std::array<uint64_t, 1> p1{9}, o1{4};
    if (!s.has("points")) s.write_dataset("points", c.points, p3);
    if (!s.has("radius")) s.write_dataset("radius", c.radius, p1);
    if (!s.has("branch_offsets")) s.write_dataset("branch_offsets", c.branch_offsets, o1);
    if (!s.has("branch_nodes")) s.write_dataset("branch_nodes", c.branch_nodes, b2);
    if (!s.has("nodes")) s.write_dataset("nodes", c.nodes, n3);
  }
  f.close();
}

std::string read_refusal_field(const fs::path& path) {
  try {
    (void)ctsurg::read_centerline_file(path);
  } catch (const ctsurg::InputError& e) {
    EXPECT_EQ(e.file(), path.string());
    return e.field();
  }
  ADD_FAILURE() << "not refused";
  return {};
}

TEST(CenterlineFile, ReaderChecksShapesAndValues) {
  TempDir dir;
  const auto c = y_centerline();
  write_raw(dir / "ok.h5", [](auto&) {});
  EXPECT_EQ(ctsurg::read_centerline_file(dir / "ok.h5").points, c.points);

  write_raw(dir / "a.h5", [&](auto& s) {
    const std::array<uint64_t, 2> p9{3, 9};
    s.write_dataset("points", c.points, p9);
  });
  EXPECT_EQ(read_refusal_field(dir / "a.h5"), "/centerline/points");
  write_raw(dir / "b.h5", [&](auto& s) {
    const std::array<uint64_t, 1> p8{8};
    s.write_dataset("radius", c.radius.data(), p8);
  });
  EXPECT_EQ(read_refusal_field(dir / "b.h5"), "/centerline/radius");
  write_raw(dir / "c.h5", [&](auto& s) {
    const std::vector<int64_t> offsets{0, 3, 6, 12};
    const std::array<uint64_t, 1> o1{4};
    s.write_dataset("branch_offsets", offsets, o1);
  });
  EXPECT_EQ(read_refusal_field(dir / "c.h5"), "/centerline/branch_offsets");
  write_raw(dir / "d.h5", [&](auto& s) {
    const std::vector<int32_t> nodes{0, 1, 1, 2, 1, -1};
    const std::array<uint64_t, 2> b2{3, 2};
    s.write_dataset("branch_nodes", nodes, b2);
  });
  EXPECT_EQ(read_refusal_field(dir / "d.h5"), "/centerline/branch_nodes");
  write_raw(dir / "e.h5", [&](auto& s) {
    const std::array<uint64_t, 2> n2{6, 2};
    s.write_dataset("nodes", c.nodes, n2);
  });
  EXPECT_EQ(read_refusal_field(dir / "e.h5"), "/centerline/nodes");
  write_raw(dir / "f.h5", [&](auto& s) { s.set_attribute("label", int64_t{70000}); });
  EXPECT_EQ(read_refusal_field(dir / "f.h5"), "/centerline/@label");
  write_raw(dir / "g.h5", [&](auto& s) {
    const std::array<double, 2> two{1, 1};
    s.set_attribute("source_spacing_mm", std::span<const double>(two));
  });
  EXPECT_EQ(read_refusal_field(dir / "g.h5"), "/centerline/@source_spacing_mm");
  write_raw(dir / "h.h5", [&](auto& s) {
    std::vector<double> r = c.radius;
    r[3] = -2.0;
    const std::array<uint64_t, 1> p1{9};
    s.write_dataset("radius", r, p1);
  });
  EXPECT_EQ(read_refusal_field(dir / "h.h5"), "/centerline/radius");
  // Not a centerline file at all.
  write_raw(dir / "i.h5", [](auto& s) { s.set_attribute("branches", int64_t{0}); });
  EXPECT_EQ(read_refusal_field(dir / "i.h5"), "/centerline/@branches");
}

}  // namespace
