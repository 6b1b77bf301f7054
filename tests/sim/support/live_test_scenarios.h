// The live tests' model and their check that two trajectories are the same (tests/sim/live).
#pragma once

#include "ctsurg/core/trajectory_file.h"

#include <gtest/gtest.h>

#include <string>

namespace ctsurg::sim::test {

// The 16 x 4 x 4 bar of 2 mm cells (write_block_files(dir, 16, 4, 4, 2.0): cell centres x 12..42,
// y -18..-12, z 32..38 mm), its x = 12 end fixed; no tools of its own. `extra_time`: more lines of its
// time: section; `frame_interval_s`: its output frames.
inline std::string live_bar_text(const std::string& extra_time = "", const std::string& frame_interval_s = "0.01") {
  return "ctsurg_scenario: 1\nname: live bar\nmodel:\n  kind: spring_grid\n  grid: grid.h5\n  surface: surface.h5\n"
         "material:\n  youngs_modulus_pa: 20000\n  damping_per_s: 30\n"
         "fixed:\n  - box_fraction: {min: [0, 0, 0], max: [0.01, 1, 1]}\n"
         "time:\n  duration_s: 1\n" + extra_time + "output:\n  trajectory: out.h5\n  frame_interval_s: " +
         frame_interval_s + "\n";
}

// Every array of two trajectories equal, bit for bit: times, surfaces, topologies, tools, metrics.
inline void expect_same_trajectory(const Trajectory& a, const Trajectory& b) {
  ASSERT_EQ(a.time, b.time);
  EXPECT_EQ(a.rest_vertices, b.rest_vertices);
  EXPECT_EQ(a.vertices, b.vertices);  // every coordinate bit for bit
  EXPECT_EQ(a.topologies, b.topologies);
  EXPECT_EQ(a.topology_of_frame, b.topology_of_frame);
  EXPECT_EQ(a.closing_triangles, b.closing_triangles);
  EXPECT_EQ(a.sphere_kinds, b.sphere_kinds);
  EXPECT_EQ(a.spheres, b.spheres);
  EXPECT_EQ(a.blades, b.blades);
  EXPECT_EQ(a.dt_s, b.dt_s);
  ASSERT_EQ(a.metrics.size(), b.metrics.size());
  for (size_t m = 0; m < a.metrics.size(); ++m) {
    EXPECT_EQ(a.metrics[m].name, b.metrics[m].name);
    EXPECT_EQ(a.metrics[m].values, b.metrics[m].values) << a.metrics[m].name;
  }
}

}  // namespace ctsurg::sim::test
