// An anti-aliased tissue mask: a smooth function whose zero level set keeps every voxel of a label
// mask on its side (inside voxels >= +margin, outside voxels <= -margin) and otherwise stays as
// close as it can to the Gaussian-smoothed mask, so that its normals follow the organ, neither the
// voxel staircase nor a smoothing that thins walls away.
//
// Method:
//   0. The mask's own lattice. A mask resampled by nearest neighbour from a coarser segmentation
//      (the bundled heart: a 3 mm segmentation on the 1.5 mm CT) is made of k x k x k blocks; its
//      staircase has steps of k voxels, and only the blocks' centres carry information. Such blocks
//      (an integer factor 2 .. max_factor per axis, found from the slices where the mask changes:
//      mask_blocks) are collapsed into one voxel each and the field is computed on that lattice;
//      there the constraints below hold at the blocks' centres. A non-integer resampling (blocks
//      of 2 and 3 voxels) is not recognised and is treated as full resolution.
//   1. g = (G_sigma * indicator - 1/2) sqrt(2 pi) sigma: the Gaussian-smoothed indicator scaled to a
//      signed distance in mm near the boundary (slope 1 across a plane), positive inside, saturating
//      at +-1.25 sigma. sigma (default 2 native voxels) removes the staircase, but it also moves the
//      level set across voxels at thin walls and sharp edges.
//   2. f = the field nearest to g in the norm of a Gaussian kernel K subject to the voxel
//      constraints: f = g + K (side * lambda) with one multiplier lambda >= 0 per voxel, non-zero only
//      where the constraint binds, so every correction is a smooth Gaussian bump (a pointwise clamp
//      would put the staircase back; a biharmonic correction has a cone-shaped Green's function in
//      3D and dents the surface at every contact: both tried, docs/mesh.md). The multipliers come
//      from projected dual ascent, lambda <- max(0, lambda + margin - side * f), with FISTA momentum
//      (Beck & Teboulle 2009) and gradient restart (O'Donoghue & Candes 2015). A wide K spreads each
//      correction smoothly but converges slowly where a thin structure needs a sharp one, so it runs
//      in stages, each from the last one's f: K of correction_sigma_voxels (default 4) for
//      stage_iterations, then half that width, then a quarter (at least kNarrowestCorrection) until
//      no voxel is on the wrong side by more than tolerance x h; what remains is clamped, so the
//      constraint holds exactly at every native voxel.
//   3. Trilinear interpolation back onto the mask's lattice.
// This is Whitaker's constraint (2000, "Reducing aliasing artifacts in iso-surfaces of binary
// volumes", IEEE VolVis; ITK's AntiAliasBinaryImageFilter) with another energy: his curvature flow
// minimises area and leaves facets between the voxels it touches (measured in docs/mesh.md).
//
// Work is on the tissue's bounding box plus a margin (the rest of the lattice gets the far-outside
// value -1.25 sigma). Parallel (OpenMP), deterministic, thread-count independent (sums over fixed
// blocks).
#pragma once

#include <array>
#include <cstdint>

#include "ctsurg/core/volume.h"

namespace ctsurg {

// A mask made of nearest-neighbour blocks: along axis a, voxels o[a] + m k[a] .. o[a] + (m + 1) k[a] - 1
// share a value (k = 1: no blocks).
struct MaskBlocks {
  std::array<int, 3> factor{1, 1, 1};
  std::array<int, 3> offset{0, 0, 0};
};

// Blocks are reported along an axis when the mask changes between at least kMinBlockChanges slice
// pairs and all of them lie k apart (k = the gcd of their distances, 2 <= k <= max_factor).
inline constexpr int kMinBlockChanges = 6;
MaskBlocks mask_blocks(const Volume<uint16_t>& labels, int max_factor = 8);

inline constexpr double kDefaultSigmaVoxels = 2.0;
inline constexpr double kNarrowestCorrection = 0.75;  // native voxels

struct AntiAliasOptions {
  double sigma_mm = -1.0;                // Gaussian of g, mm; < 0: kDefaultSigmaVoxels x the largest native spacing
  double correction_sigma_voxels = 4.0;  // width of the first stage's kernel K, native voxels (of the smallest spacing h)
  int stage_iterations = 50;             // dual iterations of each stage but the last
  int max_iterations = 500;              // dual iterations of the last stage at most
  double margin = 0.01;                  // constraint margin, x h
  double tolerance = 0.02;               // the last stage stops when no voxel is on the wrong side by more than this x h
  bool detect_blocks = true;             // work on the mask's own lattice (mask_blocks)
  int threads = 0;                       // OpenMP threads; 0 = OpenMP's default
};

struct AntiAliasStats {
  MaskBlocks blocks;  // the native lattice used
  int iterations = 0;
  double start_violation_mm = 0.0;  // largest violation by g
  double last_violation_mm = 0.0;   // ... and after the last iteration (before clamping)
  int64_t clamped_voxels = 0;       // native voxels clamped at the end
};

// labels: label mask on any lattice (tissue = label != 0; spacing in mm, index x fastest). Returns
// f on the same lattice, in mm (about the signed distance near the surface, positive inside); the
// surface is f = 0. An empty mask gives -1.25 sigma everywhere, a full one +1.25 sigma.
// InputError("--sigma-mm", ...) for a non-finite or non-positive sigma, or one wider than the lattice.
Volume<float> anti_aliased_mask(const Volume<uint16_t>& labels, const AntiAliasOptions& options = {},
                                AntiAliasStats* stats = nullptr);

}  // namespace ctsurg
