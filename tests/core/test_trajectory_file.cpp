// Tests for core/include/ctsurg/core/trajectory_file.h: round trip of every array and attribute
// (topology changes, metrics, tools, optional particles), the XDMF sidecar, and validation errors.
#include "ctsurg/core/trajectory_file.h"

#include "ctsurg/core/error.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <hdf5.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

namespace fs = std::filesystem;
using ctsurg::test::TempDir;
using ctsurg::test::test_provenance;

namespace {

// A tetrahedron's surface over three frames, moving up 1 mm per frame; frame 2 lost a triangle.
ctsurg::Trajectory three_frames(bool particles) {
  ctsurg::Trajectory t;
  t.scenario = "unit";
  t.model = "spring_grid";
  t.surface_file = "surface.h5";
  t.surface_sha256 = std::string(64, 'a');
  t.dt_s = 1e-4;
  t.time = {0.0, 0.01, 0.02};
  t.rest_vertices = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  for (int f = 0; f < 3; ++f) {
    for (int v = 0; v < 4; ++v) {
      for (int c = 0; c < 3; ++c) t.vertices.push_back(t.rest_vertices[v * 3 + c] + (c == 2 ? float(f) : 0.f));
    }
  }
  t.topologies = {{0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3}, {0, 2, 1, 0, 1, 3, 0, 3, 2}};
  t.topology_of_frame = {0, 0, 1};
  t.metrics = {{"kinetic_energy", "nJ", {0, 1.5, 2}}, {"springs_cut", "1", {0, 0, 7}}};
  t.sphere_kinds = {"grab", "probe"};
  t.spheres.assign(3 * 2 * 4, 0.0);
  t.spheres[4 + 3] = 2.5;  // frame 0, probe radius
  t.blades.assign(3 * 1 * 7, 0.0);
  t.blades[2 * 7 + 6] = 1.0;  // frame 2: blade active
  if (particles) {
    t.rest_particles = {0.5f, 0.5f, 0.5f};
    t.particles = {0.5f, 0.5f, 0.5f, 0.5f, 0.5f, 1.5f, 0.5f, 0.5f, 2.5f};
  }
  return t;
}

// Expects validate_trajectory to refuse `bad`, naming `field`.
void refused(const ctsurg::Trajectory& bad, const std::string& field) {
  try {
    ctsurg::validate_trajectory(bad, "x.h5");
    ADD_FAILURE() << "accepted a bad " << field;
  } catch (const ctsurg::InputError& e) {
    EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
  }
}

std::string read_trajectory_text(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

TEST(TrajectoryFile, RoundTripKeepsEveryArray) {
  for (const bool particles : {false, true}) {
    TempDir dir;
    const fs::path p = dir.path() / "traj.h5";
    const auto t = three_frames(particles);
    ctsurg::write_trajectory_file(p, t, test_provenance());
    const auto r = ctsurg::read_trajectory_file(p);
    EXPECT_EQ(r.scenario, t.scenario);
    EXPECT_EQ(r.model, t.model);
    EXPECT_EQ(r.surface_file, t.surface_file);
    EXPECT_EQ(r.surface_sha256, t.surface_sha256);
    EXPECT_EQ(r.dt_s, t.dt_s);
    EXPECT_EQ(r.time, t.time);
    EXPECT_EQ(r.rest_vertices, t.rest_vertices);
    EXPECT_EQ(r.vertices, t.vertices);
    EXPECT_EQ(r.topologies, t.topologies);
    EXPECT_EQ(r.topology_of_frame, t.topology_of_frame);
    ASSERT_EQ(r.metrics.size(), 2u);
    EXPECT_EQ(r.metrics[0].name, "kinetic_energy");
    EXPECT_EQ(r.metrics[0].units, "nJ");
    EXPECT_EQ(r.metrics[1].values, t.metrics[1].values);
    ASSERT_NE(r.metric("springs_cut"), nullptr);
    EXPECT_EQ(r.metric("nothing"), nullptr);
    EXPECT_EQ(r.sphere_kinds, t.sphere_kinds);
    EXPECT_EQ(r.spheres, t.spheres);
    EXPECT_EQ(r.blades, t.blades);
    EXPECT_EQ(r.blade_count(), 1);
    EXPECT_EQ(r.rest_particles, t.rest_particles);
    EXPECT_EQ(r.particles, t.particles);
    EXPECT_EQ(r.frame_triangles(2).size(), 9u);
    EXPECT_FLOAT_EQ(r.frame_vertices(2)[2], 2.f);
    // The sidecar is a temporal collection with one grid per frame and the topology each frame uses.
    const std::string x = read_trajectory_text(dir.path() / "traj.xdmf");
    EXPECT_NE(x.find("CollectionType=\"Temporal\""), std::string::npos);
    EXPECT_NE(x.find("<Time Value=\"0.02\"/>"), std::string::npos);
    EXPECT_NE(x.find("traj.h5:/trajectory/surface/topologies/1"), std::string::npos);
    EXPECT_EQ(x.find("particles 0") != std::string::npos, particles);
  }
}

TEST(TrajectoryFile, NoToolsAndNoMetricsRoundTrip) {
  TempDir dir;
  auto t = three_frames(false);
  t.sphere_kinds.clear();
  t.spheres.clear();
  t.blades.clear();
  t.metrics.clear();
  ctsurg::write_trajectory_file(dir.path() / "t.h5", t, test_provenance());
  const auto r = ctsurg::read_trajectory_file(dir.path() / "t.h5");
  EXPECT_EQ(r.sphere_count(), 0);
  EXPECT_EQ(r.blade_count(), 0);
  EXPECT_TRUE(r.metrics.empty());
  EXPECT_EQ(r.vertices, t.vertices);
}

TEST(TrajectoryFile, InconsistentArraysAreRefusedAndNothingIsWritten) {
  TempDir dir;
  const fs::path p = dir.path() / "bad.h5";
  const auto expect_refused = [&](ctsurg::Trajectory t, const std::string& field) {
    try {
      ctsurg::write_trajectory_file(p, t, test_provenance());
      ADD_FAILURE() << "accepted a trajectory with a bad " << field;
    } catch (const ctsurg::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(p));
    EXPECT_FALSE(fs::exists(dir.path() / "bad.xdmf"));
  };
  auto t = three_frames(false);
  t.vertices.pop_back();
  expect_refused(t, "/trajectory/surface/vertices");
  t = three_frames(false);
  t.topologies[1][0] = 4;
  expect_refused(t, "/trajectory/surface/topologies/1");
  t = three_frames(false);
  t.topology_of_frame[2] = 2;
  expect_refused(t, "topology_of_frame");
  t = three_frames(false);
  t.time[2] = 0.01;
  expect_refused(t, "/trajectory/time");
  t = three_frames(false);
  t.metrics[0].values.pop_back();
  expect_refused(t, "/trajectory/metrics/kinetic_energy");
  t = three_frames(false);
  t.spheres.pop_back();
  expect_refused(t, "/trajectory/tools/spheres");
  t = three_frames(true);
  t.particles.pop_back();
  expect_refused(t, "/trajectory/particles");
}

TEST(TrajectoryFile, OtherFilesAreRefusedByName) {
  TempDir dir;
  const fs::path p = dir.path() / "not.h5";
  std::ofstream(p) << "not hdf5";
  try {
    (void)ctsurg::read_trajectory_file(p);
    ADD_FAILURE() << "read a text file as a trajectory";
  } catch (const ctsurg::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not.h5"), std::string::npos) << e.what();
  }
}

// Issue 17: docs/sim.md promises that a trajectory never holds a non-finite value; the writer and
// the reader check it.
TEST(TrajectoryFile, NonFiniteValuesAreRefused) {
  TempDir dir;
  for (const int which : {0, 1, 2}) {
    ctsurg::Trajectory t = three_frames(true);
    if (which == 0) t.vertices[20] = std::nanf("");
    if (which == 1) t.metrics[0].values[1] = std::numeric_limits<double>::infinity();
    if (which == 2) t.particles[4] = std::nanf("");
    EXPECT_THROW(ctsurg::write_trajectory_file(dir / "t.h5", t, test_provenance()), ctsurg::InputError) << which;
    EXPECT_FALSE(fs::exists(dir / "t.h5"));
  }
}

// Sutures and closed cuts: the stitches (F, K, 7) and the closing-triangle counts (one per topology)
// round-trip; a file without them reads as none; wrong shapes and flags are refused.
TEST(TrajectoryFile, StitchesAndClosingTrianglesRoundTripAndAreChecked) {
  TempDir dir;
  auto t = three_frames(false);
  t.stitches.assign(3 * 2 * 7, 0.0);
  for (int f = 0; f < 3; ++f) {
    for (int k = 0; k < 2; ++k) {
      double* q = &t.stitches[static_cast<size_t>(7 * (2 * f + k))];
      q[0] = 10 + k;
      q[3] = 12 + k - 0.5 * f;  // tightening
      q[2] = q[5] = 650;
      q[6] = f > 0 ? 1.0 : 0.0;
    }
  }
  t.closing_triangles = {0, 1};
  ctsurg::write_trajectory_file(dir.path() / "s.h5", t, test_provenance());
  const auto r = ctsurg::read_trajectory_file(dir.path() / "s.h5");
  EXPECT_EQ(r.stitch_count(), 2);
  EXPECT_EQ(r.stitches, t.stitches);
  EXPECT_EQ(r.closing_triangles, t.closing_triangles);
  // Without either (as files before sutures): read as none.
  ctsurg::write_trajectory_file(dir.path() / "old.h5", three_frames(false), test_provenance());
  const auto old = ctsurg::read_trajectory_file(dir.path() / "old.h5");
  EXPECT_EQ(old.stitch_count(), 0);
  EXPECT_TRUE(old.closing_triangles.empty());
  auto bad = t;
  bad.stitches.pop_back();
  refused(bad, "/trajectory/tools/stitches");
  bad = t;
  bad.stitches[6] = 0.5;
  refused(bad, "/trajectory/tools/stitches");
  bad = t;
  bad.stitches[0] = std::numeric_limits<double>::quiet_NaN();
  refused(bad, "/trajectory/tools/stitches");
  bad = t;
  bad.closing_triangles = {0};
  refused(bad, "/trajectory/surface/closing_triangles");
  bad = t;
  bad.closing_triangles = {0, 4};  // topology 1 has 3 triangles
  refused(bad, "/trajectory/surface/closing_triangles");
}

// The tools' loads (sphere_loads) and an FEM's elements over its particles round-trip and are checked;
// the XDMF sidecar shows the particles as the FE mesh (quadratic: Tetrahedron_10) with a displacement.
TEST(TrajectoryFile, SphereLoadsAndElementsRoundTripAndAreChecked) {
  TempDir dir;
  auto t = three_frames(false);
  t.sphere_loads.assign(3 * 2 * 7, 0.0);
  t.sphere_loads[7 * 2] = 1.0;  // frame 1, the grab: measured
  t.sphere_loads[7 * 2 + 3] = 0.25;
  t.sphere_loads[7 * 2 + 4] = -1.5;
  // Ten particles: one quadratic tet (4 corners, 6 edge midpoints).
  t.rest_particles = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0.5f, 0, 0, 0.5f, 0.5f, 0, 0, 0.5f, 0, 0, 0, 0.5f, 0.5f, 0, 0.5f, 0, 0.5f, 0.5f};
  for (int f = 0; f < 3; ++f)
    for (size_t k = 0; k < t.rest_particles.size(); ++k) t.particles.push_back(t.rest_particles[k] + (k % 3 == 2 ? float(f) : 0.f));
  t.elements = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9};
  t.element_nodes = 10;
  ctsurg::write_trajectory_file(dir.path() / "l.h5", t, test_provenance());
  const auto r = ctsurg::read_trajectory_file(dir.path() / "l.h5");
  EXPECT_EQ(r.sphere_loads, t.sphere_loads);
  EXPECT_EQ(r.elements, t.elements);
  EXPECT_EQ(r.element_nodes, 10);
  const std::string xdmf = read_trajectory_text(dir.path() / "l.xdmf");
  EXPECT_NE(xdmf.find("TopologyType=\"Tetrahedron_10\" NumberOfElements=\"1\""), std::string::npos);
  EXPECT_NE(xdmf.find(":/trajectory/particles/elements"), std::string::npos);
  // Without either: read as none.
  ctsurg::write_trajectory_file(dir.path() / "o.h5", three_frames(true), test_provenance());
  const auto old = ctsurg::read_trajectory_file(dir.path() / "o.h5");
  EXPECT_TRUE(old.sphere_loads.empty());
  EXPECT_TRUE(old.elements.empty());
  EXPECT_EQ(old.element_nodes, 0);
  auto bad = t;
  bad.sphere_loads.pop_back();
  refused(bad, "/trajectory/tools/sphere_loads");
  bad = t;
  bad.sphere_loads[0] = 0.5;  // the measured flag
  refused(bad, "/trajectory/tools/sphere_loads");
  bad = t;
  bad.sphere_loads[3] = std::numeric_limits<double>::infinity();
  refused(bad, "/trajectory/tools/sphere_loads");
  bad = t;
  bad.elements[9] = 10;  // no such particle
  refused(bad, "/trajectory/particles/elements");
  bad = t;
  bad.element_nodes = 5;
  refused(bad, "/trajectory/particles/elements");
  bad = t;
  bad.elements.pop_back();
  refused(bad, "/trajectory/particles/elements");
}

TEST(TrajectoryFile, InstrumentsRoundTripAndAreChecked) {
  // A tetrahedral instrument at a pose per frame (active from frame 1, turned 90 degrees about z): its
  // mesh comes back once, its poses per frame; a trajectory without one reads as none.
  TempDir dir;
  auto t = three_frames(false);
  ctsurg::TrajectoryInstrument ins;
  ins.name = "probe.stl";
  ins.vertices = {0, 0, 0, 5, 0, 0, 0, 5, 0, 0, 0, 5};
  ins.triangles = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  t.instruments = {ins};
  const double h = std::sqrt(0.5);
  t.instrument_poses = {0, 1, 0, 0, 0, 10, 20, 650,  //
                        1, h, 0, 0, h, 10, 20, 648,  //
                        1, h, 0, 0, h, 10, 20, 646};
  ctsurg::write_trajectory_file(dir.path() / "i.h5", t, test_provenance());
  const auto r = ctsurg::read_trajectory_file(dir.path() / "i.h5");
  ASSERT_EQ(r.instruments.size(), 1u);
  EXPECT_EQ(r.instruments[0].name, "probe.stl");
  EXPECT_EQ(r.instruments[0].vertices, ins.vertices);
  EXPECT_EQ(r.instruments[0].triangles, ins.triangles);
  EXPECT_EQ(r.instrument_poses, t.instrument_poses);
  EXPECT_TRUE(ctsurg::read_trajectory_file([&] {
                ctsurg::write_trajectory_file(dir.path() / "none.h5", three_frames(false), test_provenance());
                return dir.path() / "none.h5";
              }())
                  .instruments.empty());
  auto bad = t;
  bad.instrument_poses.pop_back();
  refused(bad, "/trajectory/tools/instrument_poses");
  bad = t;
  bad.instrument_poses[1] = 2;  // not a unit quaternion
  refused(bad, "/trajectory/tools/instrument_poses");
  bad = t;
  bad.instruments[0].triangles[0] = 4;  // no vertex 4
  refused(bad, "/trajectory/tools/instruments/0/triangles");
  bad = t;
  bad.instruments[0].vertices[0] = std::numeric_limits<float>::infinity();
  refused(bad, "/trajectory/tools/instruments/0/vertices");
}

// The FEM local region: (F, V) flags round-trip (and reach the XDMF sidecar as a scalar attribute); a
// file without them reads as empty; a wrong shape or a flag above 2 is refused naming the dataset, by
// the writer and by the reader (a file another writer changed).
TEST(TrajectoryFile, VertexRegionRoundTripsAndIsChecked) {
  TempDir dir;
  auto t = three_frames(false);
  t.vertex_region = {0, 0, 0, 0,  //
                     1, 2, 0, 0,  //
                     1, 1, 2, 0};
  ctsurg::write_trajectory_file(dir.path() / "r.h5", t, test_provenance());
  const auto r = ctsurg::read_trajectory_file(dir.path() / "r.h5");
  EXPECT_EQ(r.vertex_region, t.vertex_region);
  ASSERT_NE(r.frame_region(2), nullptr);
  EXPECT_EQ(r.frame_region(2)[2], 2);
  const std::string x = read_trajectory_text(dir.path() / "r.xdmf");
  EXPECT_NE(x.find("Name=\"local_region\""), std::string::npos);
  EXPECT_NE(x.find("r.h5:/trajectory/surface/vertex_region"), std::string::npos);
  // Without it (as every run without a local region, and files from before): empty, no attribute.
  ctsurg::write_trajectory_file(dir.path() / "none.h5", three_frames(false), test_provenance());
  const auto none = ctsurg::read_trajectory_file(dir.path() / "none.h5");
  EXPECT_TRUE(none.vertex_region.empty());
  EXPECT_EQ(none.frame_region(0), nullptr);
  EXPECT_EQ(read_trajectory_text(dir.path() / "none.xdmf").find("local_region"), std::string::npos);

  auto bad = t;
  bad.vertex_region.pop_back();
  refused(bad, "/trajectory/surface/vertex_region");
  bad = t;
  bad.vertex_region[5] = 3;
  refused(bad, "/trajectory/surface/vertex_region");
  EXPECT_THROW(ctsurg::write_trajectory_file(dir.path() / "bad.h5", bad, test_provenance()), ctsurg::InputError);
  EXPECT_FALSE(fs::exists(dir.path() / "bad.h5"));

  const auto read_refused = [&](const fs::path& path, const std::string& why) {
    try {
      ctsurg::read_trajectory_file(path);
      ADD_FAILURE() << "read " << why;
    } catch (const ctsurg::InputError& e) {
      EXPECT_NE(std::string(e.what()).find("/trajectory/surface/vertex_region"), std::string::npos) << why << ": " << e.what();
    }
  };
  {  // another writer puts a flag 7 into the file (HDF5 recomputes its checksum)
    const hid_t file = H5Fopen((dir.path() / "r.h5").c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    const hid_t ds = H5Dopen2(file, "/trajectory/surface/vertex_region", H5P_DEFAULT);
    std::vector<uint8_t> flags = t.vertex_region;
    flags[9] = 7;
    ASSERT_GE(H5Dwrite(ds, H5T_NATIVE_UINT8, H5S_ALL, H5S_ALL, H5P_DEFAULT, flags.data()), 0);
    H5Dclose(ds);
    H5Fclose(file);
  }
  read_refused(dir.path() / "r.h5", "a flag 7");
  {  // ... or replaces it with one of (F, V + 1)
    const hid_t file = H5Fopen((dir.path() / "none.h5").c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    const hsize_t dims[2] = {3, 5};
    const hid_t space = H5Screate_simple(2, dims, nullptr);
    const hid_t ds = H5Dcreate2(file, "/trajectory/surface/vertex_region", H5T_NATIVE_UINT8, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    const std::vector<uint8_t> flags(15, 1);
    ASSERT_GE(H5Dwrite(ds, H5T_NATIVE_UINT8, H5S_ALL, H5S_ALL, H5P_DEFAULT, flags.data()), 0);
    H5Dclose(ds);
    H5Sclose(space);
    H5Fclose(file);
  }
  read_refused(dir.path() / "none.h5", "a (3, 5) region for 4 vertices");
}
