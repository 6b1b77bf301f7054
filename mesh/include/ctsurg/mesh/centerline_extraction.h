// The centerline of a tubular mask (a vessel): its curve skeleton as a graph of polylines between end
// points and junctions, each point with its maximal inscribed radius (core/centerline_file.h).
//
// Method, in passes (all on the mask's bounding box plus one voxel, index order x fastest):
//  1. Refusals: an empty mask; several 26-connected pieces (named with their sizes) unless the largest
//     is kept. Cavities (background not 6-connected to the outside) are filled: a hole inside a
//     segmented vessel is noise, and 26/6 thinning would keep a closed surface around it.
//  2. Exact Euclidean distance transform in mm (Felzenszwalb & Huttenlocher 2012, "Distance transforms
//     of sampled functions", separable lower envelopes of parabolas, weighted by the spacing of each
//     axis, so anisotropic voxels are exact), twice. DT(v), the distance from v's centre to the nearest
//     background centre, the outside of the image counting as background, orders the thinning and
//     sizes spurs: a vessel cut by the field of view is thinned as if capped there, so its centerline
//     ends about a radius short of the cut (with the border open, the equal DT along the axis left the
//     end to the thinning's tie-breaking, and it wandered along the cut face). The radii (pass 8) come
//     from the feature transform of the background inside the image alone, so they stay right up to
//     the border.
//  3. Distance-ordered homotopic thinning (Pudney 1998, "Distance-ordered homotopic thinning: a
//     skeletonization algorithm for 3D digital images", CVIU 72(3)): border voxels are deleted in
//     increasing DT (ties by index, so the result is deterministic) when they are simple for the 26/6
//     topology (Bertrand & Malandain 1994: one 26-component of the object in N26*, one 6-component of
//     the background in N18 that is 6-adjacent to the centre) and are not curve end points (one
//     26-neighbour); each deletion queues the neighbours again. The ridge of the DT goes last, so the
//     skeleton lies on the medial axis instead of wherever a layer-by-layer peel happens to stop. It is
//     a one-voxel-thin 26-connected curve with the mask's topology.
//  4. The skeleton graph: voxels of degree 1 are end points, 26-connected voxels of degree >= 3 one
//     junction node (at its voxel of largest DT). Junctions joined by a branch shorter than
//     `junction_merge_factor` x their radius (at least 2 voxels) become one node (the staircase splits
//     one junction into several). Spurs (a branch from an end point to a junction shorter than
//     `spur_length_factor` x the junction's radius) are pruned, least DT summed along them first (of two
//     prongs at a vessel's end, the one into a thin corner goes), never leaving a junction
//     with fewer than 2 branches, until none is left: a bump of the staircase or of noise gives a spur
//     about as long as the radius, a real branch is much longer.
//  5. Loops (a tunnel through the mask: two vessels touching, a hole in a wall) are refused with where
//     they are; `break_loops` instead cuts each loop at its thinnest voxel (the loop's branches left out
//     of a maximum spanning tree weighted by radius are the thinnest of their cycles), because a false
//     contact of two vessels is usually the thinnest part of the loop.
//  6. No tubular part (a blob: a skeleton of one voxel, or shorter in total than `min_length_factor` x
//     the largest radius) is refused.
//  7. Each branch is smoothed in mm with Taubin's lambda/mu passes (Taubin 1995, "A signal processing
//     approach to fair surface design"; lambda 0.5, mu -0.53), ends fixed: the staircase is removed
//     without shrinking curved vessels toward their centre of curvature as plain Laplacian passes do.
//  8. Radius at each point: the distance from the (smoothed) point to the nearest background voxel
//     centre, exact through the feature transform of pass 2 (the nearest sources of the 8 voxels around
//     the point), minus `radius_correction_voxels` x h, h the rms spacing across the branch
//     (sqrt(sum_i s_i^2 (1 - t_i^2) / 2), t the unit tangent). Voxel discretisation: a mask rasterised
//     from a surface puts the boundary between the last inside and the first outside centre, so for a
//     flat boundary the outside centre is half a voxel beyond it on average; but a round cross-section
//     has many outside centres around it and the nearest lies almost on the surface. Measured on the
//     tubes of tests/mesh/test_centerline_extraction.cpp (radius 2.6 to 5.5 voxels), no correction
//     gives a mean error of -0.02 to -0.13 voxel, half a voxel -0.5: the default is 0 (docs/mesh.md).
//     Interpolating the DT instead cuts the ridge's peak (-0.3 voxel more).
//
// Geometry: points in LPS mm through the mask's geometry (direction matrix included). Distances use
// the spacing alone, exact for the orthonormal direction matrices of ordinary scans; a gantry-tilted
// (sheared) lattice gives distances off by the cosine of the tilt.
#pragma once

#include "ctsurg/core/centerline_file.h"
#include "ctsurg/core/volume.h"

#include <cstdint>
#include <string>
#include <vector>

namespace ctsurg {

struct CenterlineOptions {
  double spur_length_factor = 2.0;     // a terminal branch shorter than this x the junction's radius is a spur
  double junction_merge_factor = 1.0;  // junctions closer than this x their radius (>= 2 voxels) are one node
  int smoothing_iterations = 10;       // Taubin lambda/mu pass pairs on each branch, ends fixed (0: none)
  double min_length_factor = 3.0;      // refuse when the total length is under this x the largest radius
  double radius_correction_voxels = 0.0;   // subtracted from the boundary distance, voxels across the branch
  bool keep_largest_component = false;     // several pieces: keep the largest instead of refusing
  bool break_loops = false;                // a loop: cut it at its thinnest voxel instead of refusing
};

// InputError("--<option>", "", ...) for a value out of range (factors >= 0 and finite,
// min_length_factor > 0, smoothing_iterations in [0, 1000], radius_correction_voxels in [0, 1]).
void validate_centerline_options(const CenterlineOptions& options);
// The options as JSON (Centerline::parameters).
std::string centerline_options_json(const CenterlineOptions& options);

// What extraction found and did, for the tool's log.
struct CenterlineReport {
  int64_t mask_voxels = 0;            // non-zero voxels given
  std::vector<int64_t> component_sizes;  // voxels of each 26-connected piece, largest first
  int64_t filled_cavity_voxels = 0;
  int64_t skeleton_voxels = 0;        // after thinning, before pruning
  int64_t pruned_spurs = 0;
  int64_t merged_junctions = 0;
  int64_t broken_loops = 0;
  double length_mm = 0.0;             // total length of the branches
  double max_radius_mm = 0.0;
};

// The centerline of `mask` (non-zero = inside; geometry in LPS mm, x fastest).
//   mask     dims d0 x d1 x d2, any spacing and direction (see above)
//   options  see CenterlineOptions (validated here)
//   file     the mask's file name, for messages
//   report   optional: what was found and done
// Returns points, radius (mm), branches and nodes; label 0 and source_spacing_mm = the mask's spacing,
// parameters = centerline_options_json(options). Deterministic: the same mask gives the same result.
// InputError(file, "mask", ...) for an empty mask, several pieces (how many, their sizes), a loop
// (its LPS position and radius), no tubular part; InputError from validate_centerline_options.
Centerline extract_centerline(const Volume<uint8_t>& mask, const CenterlineOptions& options, const std::string& file,
                              CenterlineReport* report = nullptr);

}  // namespace ctsurg
