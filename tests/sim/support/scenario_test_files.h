// Input files for scenario tests: a block of tissue as an occupancy grid file and its marching-cubes
// surface (as ctsurg-grid and ctsurg-surface write them), and a structured tet mesh of the bar.
// Shared by test_scenario_run.cpp, test_stress.cpp and test_scenario_gpu.cpp.
#pragma once

#include "block_surface.h"
#include "ctsurg/core/occupancy_grid_file.h"
#include "ctsurg/core/surface_mesh_file.h"
#include "ctsurg/core/tet_mesh_file.h"
#include "ctsurg/sim/fem/fem_box_mesh.h"
#include "sim_test_models.h"
#include "test_support.h"

#include <filesystem>

namespace ctsurg::sim::test {

// An nx x ny x nz block of h mm cells (block_occupancy: cell centres from (10, -20, 30) + h, shifted by
// z_offset mm), written as `dir`/grid.h5 (occupancy, fractions, label 1 "bar", mask) and its padded
// marching-cubes surface `dir`/surface.h5.
inline void write_block_files(const std::filesystem::path& dir, int nx, int ny, int nz, double h, double z_offset = 0) {
  OccupancyGrid g;
  g.occupancy = block_occupancy(nx, ny, nz, h);
  g.occupancy.geometry.origin.z() += z_offset;
  g.fraction = Volume<float>(g.occupancy.geometry, 0.f);
  g.label = Volume<uint16_t>(g.occupancy.geometry, 0);
  for (size_t i = 0; i < g.occupancy.voxels.size(); ++i) {
    g.fraction.voxels[i] = g.occupancy.voxels[i] ? 1.f : 0.f;
    g.label.voxels[i] = g.occupancy.voxels[i] ? 1 : 0;
  }
  g.mask = g.label;
  g.label_names = {{1, "bar"}};
  write_occupancy_grid_file(dir / "grid.h5", g, ctsurg::test::test_provenance());
  write_surface_mesh_file(dir / "surface.h5", block_surface(g.fraction),
                          ctsurg::test::test_provenance());
}

// The 16 x 4 x 4 bar of 2 mm cells (solid x 11..43, y -19..-11, z 31..39 mm) as a structured tet mesh
// (8 x 2 x 2 cells of 4 mm, Kuhn tets), `dir`/tetmesh.h5.
inline void write_bar_tet_mesh(const std::filesystem::path& dir) {
  write_tet_mesh_file(dir / "tetmesh.h5", tet_mesh_of(fem_box_mesh({8, 2, 2}, {32, 8, 8}, {11, -19, 31})),
                      ctsurg::test::test_provenance());
}

}  // namespace ctsurg::sim::test
