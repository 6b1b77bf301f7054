// The full-resolution field a normal map takes its detail from: a scalar volume whose level set
// {f = iso} is the detailed organ surface (inside = f >= iso), smooth enough that its gradient, the
// surface normal, does not show the voxel staircase of a label mask: for a mask the anti-aliased
// mask (anti_aliased_mask.h: smooth, yet every voxel on its side), or a Gaussian-smoothed indicator;
// for a CT its Gaussian-smoothed values.
//
// Sampling is trilinear on the voxel-centre lattice (clamped to the lattice at its border). The
// gradient is the trilinear interpolation of central-difference gradients at the 8 surrounding
// nodes (one-sided on the border), so it is continuous across cells, mapped from index space to LPS
// by the inverse transpose of the index-to-world matrix (as marching_cubes.cpp does for normals).
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "ctsurg/core/volume.h"
#include "ctsurg/mesh/anti_aliased_mask.h"

namespace ctsurg {

struct DetailField {
  Volume<float> values;                                                 // the smoothed field on the full-resolution lattice
  double iso = 0.5;                                                     // the surface; inside = values >= iso
  Eigen::Matrix3d world_to_index_linear = Eigen::Matrix3d::Identity();  // inverse of index_to_world_matrix()
};

// Separable Gaussian blur with standard deviation sigma_mm (converted per axis to voxels through
// the spacing; the kernel is truncated at 3 sigma and renormalised; edges clamped). sigma_mm = 0
// returns the input. Parallel over lines (OpenMP); deterministic. InputError("--sigma-mm", ...)
// for a negative or non-finite sigma.
Volume<float> gaussian_smoothed(const Volume<float>& field, double sigma_mm, int threads = 0);

// The indicator of the tissue (label != 0) of a label mask (full-resolution lattice), smoothed with
// sigma_mm; iso 0.5.
DetailField detail_field_from_labels(const Volume<uint16_t>& labels, double sigma_mm, int threads = 0);
// The anti-aliased mask of the tissue (label != 0), in mm, iso 0 (anti_aliased_mask.h).
DetailField detail_field_from_anti_aliased_labels(const Volume<uint16_t>& labels, const AntiAliasOptions& options = {},
                                                  AntiAliasStats* stats = nullptr);
// A scalar field (e.g. HU) smoothed with sigma_mm, surface at iso (same units as the field).
DetailField detail_field_from_values(const Volume<float>& values, double iso, double sigma_mm, int threads = 0);

// Value of the field at LPS point p (mm), trilinear, clamped at the lattice border.
double sample_value(const DetailField& field, const Eigen::Vector3d& p_mm);
// Gradient of the field at p, LPS, field units per mm.
Eigen::Vector3d sample_gradient(const DetailField& field, const Eigen::Vector3d& p_mm);

}  // namespace ctsurg
