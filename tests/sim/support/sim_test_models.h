// Small models shared by the sim tests: occupancy blocks and deterministic perturbations.
#pragma once

#include "ctsurg/core/volume.h"
#include "ctsurg/sim/base/particle_state.h"
#include "ctsurg/sim/springs/spring_grid_model.h"

#include <cstdint>

namespace ctsurg::sim::test {

// An nx x ny x nz block of occupied cells with `h` mm cells, a margin of `margin` empty cells around
// it, origin (10, -20, 30) mm, identity direction.
inline Volume<uint8_t> block_occupancy(int nx, int ny, int nz, double h, int margin = 1) {
  ImageGeometry g;
  g.dims = {nx + 2 * margin, ny + 2 * margin, nz + 2 * margin};
  g.spacing = Eigen::Vector3d(h, h, h);
  g.origin = Eigen::Vector3d(10, -20, 30);
  Volume<uint8_t> v(g, 0);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) v(i + margin, j + margin, k + margin) = 1;
  return v;
}

// The block with holes: cells with (7 i + 3 j + 5 k) % 11 == 0 removed, so rows break irregularly and the
// step kernel takes both its contiguous and its gathering paths.
inline Volume<uint8_t> holed_block_occupancy(int nx, int ny, int nz, double h) {
  auto v = block_occupancy(nx, ny, nz, h);
  for (int k = 0; k < v.geometry.dims[2]; ++k)
    for (int j = 0; j < v.geometry.dims[1]; ++j)
      for (int i = 0; i < v.geometry.dims[0]; ++i)
        if ((7 * i + 3 * j + 5 * k) % 11 == 0) v(i, j, k) = 0;
  return v;
}

inline SpringGridMaterial test_material(double k_face = 1000, double k_edge = 1000, double damping = 0) {
  SpringGridMaterial m;
  m.density = 1e-3;
  m.face_stiffness = k_face;
  m.edge_stiffness = k_edge;
  m.face_damping = damping;
  m.edge_damping = damping;
  return m;
}

// Moves every particle (current and previous position alike: zero velocity) by a pseudo-random offset
// in [-amplitude, amplitude]^3 mm; a fixed 64-bit LCG, so every platform gets the same numbers.
inline void perturb(ParticleState& s, double amplitude, uint64_t seed = 12345) {
  auto next = [&seed] {
    seed = seed * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(seed >> 11) / static_cast<double>(1ull << 53) * 2.0 - 1.0;
  };
  for (int32_t i = 0; i < s.count(); ++i) {
    s.x[i] += static_cast<Real>(amplitude * next());
    s.y[i] += static_cast<Real>(amplitude * next());
    s.z[i] += static_cast<Real>(amplitude * next());
    s.px[i] = s.x[i], s.py[i] = s.y[i], s.pz[i] = s.z[i];
  }
}

}  // namespace ctsurg::sim::test
