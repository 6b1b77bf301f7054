// The surface of an occupancy block as ctsurg-surface makes it: marching cubes at 0.5 over the cells'
// tissue fractions (1 inside, 0 outside), padded by one empty cell where the tissue touches the border,
// with the lattice tie a grid model's surface coupling reads. Shared by the surface, spring engine and
// scenario tests.
#pragma once

#include "ctsurg/core/surface_mesh_file.h"
#include "ctsurg/core/volume.h"
#include "ctsurg/mesh/lattice_padding.h"
#include "ctsurg/mesh/marching_cubes.h"

namespace ctsurg::sim::test {

inline Volume<float> block_fraction(const Volume<uint8_t>& occupancy) {
  Volume<float> f(occupancy.geometry, 0.f);
  for (size_t i = 0; i < occupancy.voxels.size(); ++i) f.voxels[i] = occupancy.voxels[i] ? 1.f : 0.f;
  return f;
}

inline SurfaceMesh block_surface(const Volume<float>& fraction) { return marching_cubes(pad_lattice(fraction, 0.f, 1), 0.5); }
inline SurfaceMesh block_surface(const Volume<uint8_t>& occupancy) { return block_surface(block_fraction(occupancy)); }

}  // namespace ctsurg::sim::test
