// Synthetic CT phantoms with known analytic volume and surface area: the ground truth for the
// accuracy tests of every later stage (marching-cubes convergence, meshing, FEM).
//
// Shapes (all in LPS mm, centred on `centre_mm`, axes along LPS x, y, z):
//  - sphere           radius R.
//  - ellipsoid shell  the solid between the outer ellipsoid with semi-axes (a, b, c) along x, y, z
//                     and the inner one with semi-axes (a-t, b-t, c-t); t is the wall thickness
//                     measured along the axes (the wall is thinner than t elsewhere only by the
//                     ellipsoid's curvature; it is exactly t at the six axis points).
//  - torus            tube of radius r around the circle of radius R in the xy plane (axis z).
//  - bumpy sphere     star-shaped about the centre, r(theta, phi) = R (1 + eps * Y(theta, phi)) with
//                     Y = cos(m theta) sin^n(theta) cos(n phi), theta the polar angle from +z and phi
//                     the azimuth from +x. Y is chosen instead of sin(m theta) cos(n phi) because it is
//                     a polynomial in the unit vector (cos(m theta) = T_m(z), sin^n(theta) cos(n phi) =
//                     Re (x + i y)^n), so the surface is smooth at the poles too and its normals are
//                     a fair test for normal maps. |Y| <= 1, so |eps| < 1 keeps r > 0.
//
// Analytic values: sphere and torus in closed form; the ellipsoid shell's volume in closed form and
// each ellipsoid's area by Gauss-Legendre quadrature in theta times the trapezoid rule in phi
// (spectrally accurate for this smooth periodic integrand), refined until two successive orders
// agree to 1e-12 relative; the bumpy sphere's volume and area by the same quadrature.
//
// Rasterisation: each voxel gets the fraction of its box inside the shape, estimated by s^3
// supersamples at the centres of an s x s x s sub-grid, and the HU value
// outside + (inside - outside) * fraction, so that the isosurface at the mid value converges to the
// true surface as the spacing shrinks. Voxels whose box lies provably entirely inside or outside
// (a Lipschitz bound on the implicit function at the voxel centre) skip the supersampling; the
// result is the same as sampling every voxel.
#pragma once

#include "ctsurg/core/volume.h"

#include <Eigen/Core>
#include <cstdint>
#include <string>

namespace ctsurg {

enum class PhantomKind { Sphere, EllipsoidShell, Torus, BumpySphere };

// "sphere", "ellipsoid-shell", "torus", "bumpy-sphere".
const char* phantom_kind_name(PhantomKind kind);
// Inverse of phantom_kind_name; InputError(source, "KIND", ...) listing the kinds otherwise.
PhantomKind phantom_kind_from_name(const std::string& name, const std::string& source);

struct PhantomShape {
  PhantomKind kind = PhantomKind::Sphere;
  Eigen::Vector3d centre_mm{0.0, 0.0, 0.0};  // LPS mm
  double radius_mm = 20.0;                      // sphere, bumpy sphere: R
  Eigen::Vector3d semi_axes_mm{30.0, 22.0, 16.0};  // ellipsoid shell: outer a, b, c along x, y, z
  double thickness_mm = 4.0;                    // ellipsoid shell: t
  double major_mm = 25.0;                       // torus: R, centre of the tube to the axis
  double minor_mm = 8.0;                        // torus: r, tube radius
  double bump_amplitude = 0.15;                 // bumpy sphere: eps, dimensionless
  int bump_m = 3;                               // bumpy sphere: cos(m theta) factor
  int bump_n = 4;                               // bumpy sphere: sin^n(theta) cos(n phi) factor
};

// Throws InputError(source, field, problem) unless the parameters of shape.kind are valid: R, a, b,
// c, t, r positive and finite; t < min(a, b, c); r < R (torus); |eps| < 1, 0 <= m, n <= 32; centre
// finite. Fields are named as ctsurg-phantom's options ("--radius-mm", "--thickness-mm", ...), so
// a tool's message points at the option to fix.
void validate_phantom_shape(const PhantomShape& shape, const std::string& source);

// Implicit function of the shape at LPS point p (mm): negative inside, positive outside, zero
// exactly on the surface. For the sphere and torus it is the exact signed distance; for the
// ellipsoid shell and bumpy sphere it is distance-like (mm, same zero set, |value| <= distance for
// the ellipsoid shell; for the bumpy sphere it is |p - centre| - r(theta, phi), the radial gap).
double phantom_implicit_mm(const PhantomShape& shape, const Eigen::Vector3d& p_mm);
// True when p is strictly inside (phantom_implicit_mm < 0).
bool phantom_contains(const PhantomShape& shape, const Eigen::Vector3d& p_mm);

// Analytic outward unit normal (LPS) of the surface nearest to p in the sense of the implicit
// function: the normalised gradient of the shape's defining function (for the bumpy sphere the
// closed form n ~ e_r - (r_theta e_theta + r_phi / sin(theta) e_phi) / r). For the ellipsoid shell
// the inner wall's normal points into the cavity (out of the solid). Exact on the surface; off the
// surface it is the normal of the level set through p. At the centre (and on a torus's axis) it
// returns +z rather than NaN.
Eigen::Vector3d phantom_outward_normal(const PhantomShape& shape, const Eigen::Vector3d& p_mm);

// For the bumpy sphere: the surface point (LPS mm) at polar angle theta from +z and azimuth phi
// from +x (radians).
Eigen::Vector3d bumpy_sphere_surface_point(const PhantomShape& shape, double theta, double phi);

// Enclosed volume of the solid, mm^3.
double phantom_volume_mm3(const PhantomShape& shape);
// Area of the solid's whole boundary, mm^2 (for the ellipsoid shell: outer plus inner ellipsoid).
double phantom_area_mm2(const PhantomShape& shape);
// Surface area of the ellipsoid with semi-axes a, b, c (mm), mm^2, to about 1e-12 relative.
// RuntimeError if the quadrature fails to converge (extreme aspect ratios beyond 1e4).
double ellipsoid_surface_area_mm2(double a, double b, double c);
// Half-extents (mm) along x, y, z of the shape's axis-aligned bounding box about its centre.
Eigen::Vector3d phantom_half_extent_mm(const PhantomShape& shape);

struct PhantomRasterOptions {
  Eigen::Vector3d spacing_mm{1.0, 1.0, 1.0};  // voxel spacing along x, y, z (may be anisotropic)
  double margin_mm = 4.0;    // at least this much background between the bounding box and the
                             // outermost voxel centres, on every side
  int supersample = 4;       // s: s^3 samples per voxel, 1..64
  float hu_inside = 60.0f;   // soft tissue
  float hu_outside = -1000.0f;  // air
  // Where the shape's centre sits relative to the central voxel centre, in voxels along i, j, k,
  // each in [-0.5, 0.5]. 0 puts the centre on a voxel centre; convergence studies average over
  // several offsets, because the error of one fixed placement oscillates as the spacing changes.
  Eigen::Vector3d lattice_offset_voxels{0.0, 0.0, 0.0};
};

// Throws InputError(source, field, ...) for non-positive or non-finite spacing ("--spacing-mm"), a
// negative margin ("--margin-mm"), supersample outside 1..64 ("--supersample"), non-finite or equal
// HU values ("--hu-inside", "--hu-outside"), a lattice offset outside [-0.5, 0.5] ("lattice_offset_voxels").
void validate_phantom_raster_options(const PhantomRasterOptions& options, const std::string& source);

// The lattice the rasteriser uses: identity direction, the given spacing, an odd number of voxels
// per axis, dims[a] = 2 * ceil((h[a] + margin) / spacing[a] + |offset[a]|) + 1 with h the
// half-extent and offset = lattice_offset_voxels, origin = centre - spacing * ((dims - 1) / 2 +
// offset). With the default zero offset the shape's centre is the central voxel's centre.
// InputError(source, "--spacing-mm", ...) when an axis would exceed 2^31 voxels.
ImageGeometry phantom_geometry(const PhantomShape& shape, const PhantomRasterOptions& options, const std::string& source);

struct PhantomRaster {
  Volume<float> hu;       // HU per voxel, outside + (inside - outside) * fraction
  Volume<uint8_t> label;  // 1 where fraction >= 0.5, else 0; same geometry as hu
  // Sum over voxels of fraction * voxel volume, mm^3: the rasterised estimate of the volume.
  double fraction_volume_mm3 = 0.0;
};

// Rasterises `shape` on phantom_geometry(shape, options). Validates shape and options (InputError
// as above) and checks the allocation (5 bytes per voxel) against available memory
// (InputError(source, "--spacing-mm", ...)). Parallel over z-slices with OpenMP; the result does not
// depend on the thread count (integer sample counts per slice, summed in slice order).
PhantomRaster rasterise_phantom(const PhantomShape& shape, const PhantomRasterOptions& options, const std::string& source);

}  // namespace ctsurg
