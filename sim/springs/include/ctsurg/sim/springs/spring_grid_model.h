// The spring-mass model with implicit connections on a voxel grid (Mosegaard & Sorensen 2005,
// section 2.5.2; Mosegaard, Herborg & Sorensen 2005, MMVR): one particle per occupied cell, each
// connected to its 18 grid neighbours (6 across faces, rest length h; 12 across edges, rest length
// h sqrt 2), which resist stretch (structural) and shear.
//
// Storage is compact: only occupied cells are particles (their flat cell indices, increasing, give
// the compact index), and an 18-neighbour index table built once replaces the papers' texture
// offsets, so the kernels never touch empty space. Each particle has an 18-bit spring mask (bit d
// set = the spring to neighbour d is present) so that single springs can be cut, the papers' cutting
// granularity (2005, section 2.7.3). A spring (a, b) is present on a iff it is present on b.
//
// The neighbour table is direction-major (neighbours[d * P + i]): the step kernel runs one particle
// per SIMD lane (CPU) or thread (GPU), so lane i reads direction d of consecutive particles from
// consecutive addresses.
//
// Units: see particle_state.h (mm, s, g; stiffness g/s^2 = uN/mm; damping g/s).
#pragma once

#include "ctsurg/core/volume.h"
#include "ctsurg/sim/base/particle_state.h"
#include "ctsurg/sim/base/real.h"

#include <array>
#include <climits>
#include <cstdint>
#include <vector>

namespace ctsurg {
struct OccupancyGrid;  // core/occupancy_grid_file.h
}

namespace ctsurg::sim {

constexpr int kGridDirections = 18;

// Index offsets (di, dj, dk) of the 18 neighbours. Directions 0-5 cross a face, 6-17 an edge;
// direction d ^ 1 is the opposite of d.
constexpr std::array<std::array<int, 3>, kGridDirections> kGridDirectionOffsets{{
    {{1, 0, 0}}, {{-1, 0, 0}}, {{0, 1, 0}}, {{0, -1, 0}}, {{0, 0, 1}}, {{0, 0, -1}},
    {{1, 1, 0}}, {{-1, -1, 0}}, {{1, -1, 0}}, {{-1, 1, 0}},
    {{1, 0, 1}}, {{-1, 0, -1}}, {{1, 0, -1}}, {{-1, 0, 1}},
    {{0, 1, 1}}, {{0, -1, -1}}, {{0, 1, -1}}, {{0, -1, 1}},
}};
constexpr int opposite_direction(int d) { return d ^ 1; }

// Particles per chunk of the CPU step kernel (two 16-float SIMD vectors), and the chunk offset that
// marks an irregular chunk (see SpringGridModel::chunk_offsets).
constexpr int32_t kGridChunk = 32;
constexpr int32_t kIrregularChunk = INT32_MIN;
constexpr bool is_face_direction(int d) { return d < 6; }

// Material of a grid model. Stiffness per direction class; no defaults for the stiffness (a
// scenario's material preset supplies them).
struct SpringGridMaterial {
  double density = 1.06e-3;    // g/mm^3 (soft tissue, 1.06 g/cm^3)
  double face_stiffness = 0;   // g/s^2, springs to the 6 face neighbours (> 0)
  double edge_stiffness = 0;   // g/s^2, springs to the 12 edge neighbours (>= 0)
  double face_damping = 0;     // g/s, damping along face springs (>= 0)
  double edge_damping = 0;     // g/s, damping along edge springs (>= 0)
  bool mass_from_fraction = false;  // mass = density * cell volume * fraction (else * 1)
};

// What the step kernel sees (trivially copyable; the per-direction constants travel by value).
struct SpringGridView {
  const int32_t* neighbours;    // 18 x #P, direction-major, -1 = no particle there
  const uint32_t* spring_mask;  // #P, bit d = spring to neighbour d present
  const int32_t* chunk_offsets; // ceil(#P / 32) x 18 (see SpringGridModel), CPU only
  Real rest_length[kGridDirections];  // mm
  Real stiffness[kGridDirections];    // g/s^2
  Real damping[kGridDirections];      // g/s
  int32_t count;                      // #P
};

struct SpringGridModel {
  ImageGeometry lattice;                 // the occupancy grid's cell lattice (cell centres, LPS mm)
  std::vector<int64_t> cells;            // #P flat cell index (i + nx (j + ny k)) of each particle, increasing
  std::vector<int32_t> neighbours;       // 18 x #P, direction-major: neighbours[d * #P + i], -1 = none
  std::vector<uint32_t> spring_mask;     // #P, bit d set = spring to neighbour d present
  // CPU acceleration index, built once with the table: for chunk c (particles 32 c .. 32 c + 31) and
  // direction d, entry [c * 18 + d] = o when neighbours[d][i] = i + o for every particle i of the
  // chunk that has a neighbour in direction d, and 0 <= 32 c + o, 32 c + o + 32 <= #P; then the CPU
  // kernel reads the chunk's neighbours with contiguous loads (a solid region's rows: most chunks).
  // kIrregularChunk otherwise (gathered). Cutting springs does not change it.
  std::vector<int32_t> chunk_offsets;
  std::array<Real, kGridDirections> rest_length{};  // mm: |lattice matrix * offset d| (h, h sqrt 2)
  std::array<Real, kGridDirections> stiffness{};    // g/s^2
  std::array<Real, kGridDirections> damping{};      // g/s
  std::vector<Real> rest_positions;      // #P x 3, cell centres, LPS mm
  std::vector<Real> mass;                // #P g

  int32_t particle_count() const { return static_cast<int32_t>(cells.size()); }
  // The particle of cell (i, j, k), or -1 when the cell is empty or outside the lattice. O(log #P).
  int32_t particle_at(int64_t i, int64_t j, int64_t k) const;
  // Number of springs present, each counted once.
  int64_t spring_count() const;
  SpringGridView view() const;
  // A state at rest at the rest positions with the model's masses.
  ParticleState make_state() const;
};

// Builds the model from an occupancy volume (cells with value != 0 are particles).
//
// occupancy  cell lattice (isotropic cells from ctsurg-grid, though any lattice works: rest lengths
//            come from the lattice matrix), x fastest
// material   densities, stiffnesses, damping; InputError("material", field, ...) when out of range
// fraction   optional, same lattice: tissue fraction per cell, used when material.mass_from_fraction
// Throws InputError("occupancy", ...) when no cell is occupied, a fraction is missing or on another
// lattice, or there are more than 2^31 - 1 particles.
SpringGridModel build_spring_grid_model(const Volume<uint8_t>& occupancy, const SpringGridMaterial& material,
                                        const Volume<float>* fraction = nullptr);
// The same from an occupancy grid file's content (/grid/occupancy, /grid/fraction).
SpringGridModel build_spring_grid_model(const OccupancyGrid& grid, const SpringGridMaterial& material);

// Ids (increasing) of the model's particles whose cell has label `value` in `label` (/grid/label, on
// the model's lattice): a fixed region by tissue label (base/fixed_regions.h). Throws
// InputError("fixed region", "label", ...) when the lattices differ.
std::vector<int32_t> particles_with_label(const SpringGridModel& model, const Volume<uint16_t>& label, uint16_t value);

// Cuts the spring between `particle` and its neighbour in `direction` (0..17) on both particles.
// Returns false when there was no such spring (already cut, or no neighbour).
bool cut_grid_spring(SpringGridModel& model, int32_t particle, int direction);

}  // namespace ctsurg::sim
