// A structured tetrahedral mesh of an axis-aligned box, for tests, benchmarks and calibration: nx x ny x nz
// hexahedral cells, each split into 6 tets around its main diagonal (Kuhn's subdivision; the same split
// in every cell, so faces match across cells and the mesh is conforming).
#pragma once

#include "ctsurg/core/tet_mesh_file.h"

#include <array>
#include <cstdint>
#include <vector>

namespace ctsurg::sim {

struct FemBoxMesh {
  std::vector<double> nodes;   // #N x 3 mm, #N = (nx+1)(ny+1)(nz+1), node (i, j, k) at
                               // i + (nx+1) (j + (ny+1) k) (x fastest)
  std::vector<int32_t> tets;   // #T x 4, #T = 6 nx ny nz, positively oriented
};

// cells: nx, ny, nz >= 1; size: box edge lengths mm (> 0); origin: the minimum corner, mm.
// Throws InputError("fem box mesh", "cells" | "size", ...) otherwise.
FemBoxMesh fem_box_mesh(const std::array<int, 3>& cells, const std::array<double, 3>& size,
                        const std::array<double, 3>& origin = {0, 0, 0});

// The box as a ctsurg tet mesh (one label, 1; a one-bin quality histogram), for writing a tetmesh.h5
// that scenarios read.
TetMesh tet_mesh_of(const FemBoxMesh& box);

}  // namespace ctsurg::sim
