#include "ctsurg/preprocess/synthetic_phantom.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/memory_guard.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <sstream>
#include <vector>

namespace ctsurg {

namespace {

constexpr double kPi = std::numbers::pi;

std::string num(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

bool positive_finite(double v) { return std::isfinite(v) && v > 0.0; }

// ---- Quadrature over the unit sphere's (theta, phi) rectangle ----------------------------------

// Nodes and weights of the n-point Gauss-Legendre rule on [-1, 1] (Newton on P_n from the
// Chebyshev-like initial guess; Golub-Welsch would do as well).
void gauss_legendre(int n, std::vector<double>& x, std::vector<double>& w) {
  x.assign(static_cast<std::size_t>(n), 0.0);
  w.assign(static_cast<std::size_t>(n), 0.0);
  for (int i = 0; i < (n + 1) / 2; ++i) {
    double z = std::cos(kPi * (i + 0.75) / (n + 0.5));
    double dp = 0.0;
    for (int iter = 0; iter < 100; ++iter) {
      double p0 = 1.0, p1 = 0.0;
      for (int k = 1; k <= n; ++k) {
        const double p2 = p1;
        p1 = p0;
        p0 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p2) / k;
      }
      dp = n * (z * p0 - p1) / (z * z - 1.0);
      const double dz = p0 / dp;
      z -= dz;
      if (std::abs(dz) < 1e-16) break;
    }
    x[static_cast<std::size_t>(i)] = -z;
    x[static_cast<std::size_t>(n - 1 - i)] = z;
    const double wi = 2.0 / ((1.0 - z * z) * dp * dp);
    w[static_cast<std::size_t>(i)] = wi;
    w[static_cast<std::size_t>(n - 1 - i)] = wi;
  }
}

// Integral of f(theta, phi) over theta in [0, pi] (Gauss-Legendre: f is smooth but not periodic
// there) and phi in [0, 2 pi) (trapezoid rule: spectrally accurate for smooth periodic f). The
// order doubles until two successive results agree to 1e-12 relative.
template <class F>
double integrate_over_sphere(const F& f, const char* what) {
  double previous = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> x, w;
  for (int n = 16; n <= 4096; n *= 2) {
    gauss_legendre(n, x, w);
    const int n_phi = 2 * n;
    const double d_phi = 2.0 * kPi / n_phi;
    double sum = 0.0;
    for (int i = 0; i < n; ++i) {
      const double theta = 0.5 * kPi * (x[static_cast<std::size_t>(i)] + 1.0);
      double ring = 0.0;
      for (int j = 0; j < n_phi; ++j) ring += f(theta, j * d_phi);
      sum += 0.5 * kPi * w[static_cast<std::size_t>(i)] * ring * d_phi;
    }
    if (std::abs(sum - previous) <= 1e-12 * std::abs(sum)) return sum;
    previous = sum;
  }
  throw RuntimeError(std::string("synthetic phantom: quadrature for the ") + what + " did not converge");
}

// ---- Bumpy sphere: r(theta, phi) = R (1 + eps Y), Y = cos(m theta) sin^n(theta) cos(n phi) ---------

// Y from the unit direction u, as polynomials (T_m(u_z) * Re (u_x + i u_y)^n): no trigonometry,
// and no special case at the poles.
double bump_from_direction(const PhantomShape& s, const Eigen::Vector3d& u) {
  double t_prev = 1.0, t = u.z();  // Chebyshev T_0, T_1
  double cos_m_theta = 1.0;
  if (s.bump_m == 1) cos_m_theta = t;
  for (int k = 2; k <= s.bump_m; ++k) {
    const double next = 2.0 * u.z() * t - t_prev;
    t_prev = t;
    t = next;
    cos_m_theta = t;
  }
  std::complex<double> z(1.0, 0.0);
  const std::complex<double> xy(u.x(), u.y());
  for (int k = 0; k < s.bump_n; ++k) z *= xy;
  return cos_m_theta * z.real();
}

struct BumpDerivatives {
  double r;             // R (1 + eps Y)
  double r_theta;       // dr/dtheta
  double r_phi_by_sin;  // (dr/dphi) / sin(theta), finite at the poles
};

BumpDerivatives bump_derivatives(const PhantomShape& s, double theta, double phi) {
  const double re = s.radius_mm * s.bump_amplitude;
  const int m = s.bump_m, n = s.bump_n;
  const double st = std::sin(theta), ct = std::cos(theta);
  const double s_n = std::pow(st, n);
  const double s_n1 = n >= 1 ? std::pow(st, n - 1) : 0.0;
  const double cm = std::cos(m * theta), sm = std::sin(m * theta);
  const double cn = std::cos(n * phi), sn = std::sin(n * phi);
  BumpDerivatives d;
  d.r = s.radius_mm + re * cm * s_n * cn;
  d.r_theta = re * (-m * sm * s_n + n * cm * s_n1 * ct) * cn;
  d.r_phi_by_sin = -re * n * cm * s_n1 * sn;
  return d;
}

// Bound on |grad_S Y| over the unit sphere: |Y_theta| <= m + n and |Y_phi / sin(theta)| <= n.
double bump_gradient_bound(const PhantomShape& s) {
  const double m = s.bump_m, n = s.bump_n;
  return std::sqrt((m + n) * (m + n) + n * n);
}

// ---- Ellipsoid shell ---------------------------------------------------------------------------

// Lipschitz-1 implicit of the ellipsoid with semi-axes e: min(e) (|q ./ e| - 1). The gradient of
// |q ./ e| has norm at most 1 / min(e), so scaling by min(e) makes |value| <= distance to the surface.
double ellipsoid_implicit(const Eigen::Vector3d& q, const Eigen::Vector3d& e) {
  return e.minCoeff() * (q.cwiseQuotient(e).norm() - 1.0);
}

Eigen::Vector3d inner_semi_axes(const PhantomShape& s) {
  return s.semi_axes_mm - Eigen::Vector3d::Constant(s.thickness_mm);
}

Eigen::Vector3d normalized_or_z(const Eigen::Vector3d& v) {
  const double n = v.norm();
  return n > 0.0 && std::isfinite(n) ? Eigen::Vector3d(v / n) : Eigen::Vector3d::UnitZ();
}

// Box-uniformity test for the rasteriser: -1 when every point within `radius` of p is inside,
// +1 when every such point is outside, 0 when undecided. Uses |f(p)| > L * radius with L a
// Lipschitz constant of the implicit function on that ball; the small slack covers rounding.
int classify_ball(const PhantomShape& s, const Eigen::Vector3d& p, double radius) {
  const double f = phantom_implicit_mm(s, p);
  double lipschitz = 1.0;
  if (s.kind == PhantomKind::BumpySphere) {
    const double nearest = (p - s.centre_mm).norm() - radius;
    if (nearest <= 0.0) return 0;
    lipschitz = 1.0 + s.radius_mm * std::abs(s.bump_amplitude) * bump_gradient_bound(s) / nearest;
  }
  const double bound = lipschitz * radius * (1.0 + 1e-9) + 1e-9;
  if (f < -bound) return -1;
  if (f > bound) return 1;
  return 0;
}

}  // namespace

const char* phantom_kind_name(PhantomKind kind) {
  switch (kind) {
    case PhantomKind::Sphere: return "sphere";
    case PhantomKind::EllipsoidShell: return "ellipsoid-shell";
    case PhantomKind::Torus: return "torus";
    case PhantomKind::BumpySphere: return "bumpy-sphere";
  }
  return "?";
}

PhantomKind phantom_kind_from_name(const std::string& name, const std::string& source) {
  for (PhantomKind k : {PhantomKind::Sphere, PhantomKind::EllipsoidShell, PhantomKind::Torus, PhantomKind::BumpySphere}) {
    if (name == phantom_kind_name(k)) return k;
  }
  throw InputError(source, "KIND",
                   "unknown phantom kind '" + name + "'; expected sphere, ellipsoid-shell, torus or bumpy-sphere");
}

void validate_phantom_shape(const PhantomShape& s, const std::string& source) {
  if (!s.centre_mm.allFinite()) throw InputError(source, "--centre-mm", "centre must be finite LPS mm");
  auto require_positive = [&](double v, const char* field) {
    if (!positive_finite(v)) throw InputError(source, field, "must be a positive, finite number of mm, got " + num(v));
  };
  switch (s.kind) {
    case PhantomKind::Sphere: require_positive(s.radius_mm, "--radius-mm"); break;
    case PhantomKind::BumpySphere:
      require_positive(s.radius_mm, "--radius-mm");
      if (!(std::abs(s.bump_amplitude) < 1.0)) {
        throw InputError(source, "--bump-amplitude", "must lie in (-1, 1) so the radius stays positive, got " + num(s.bump_amplitude));
      }
      if (s.bump_m < 0 || s.bump_m > 32) throw InputError(source, "--bump-m", "must be an integer in 0..32, got " + std::to_string(s.bump_m));
      if (s.bump_n < 0 || s.bump_n > 32) throw InputError(source, "--bump-n", "must be an integer in 0..32, got " + std::to_string(s.bump_n));
      break;
    case PhantomKind::EllipsoidShell:
      for (int a = 0; a < 3; ++a) {
        if (!positive_finite(s.semi_axes_mm[a])) {
          throw InputError(source, "--semi-axes-mm",
                           "semi-axis " + std::string(1, "abc"[a]) + " must be a positive, finite number of mm, got " +
                               num(s.semi_axes_mm[a]));
        }
      }
      require_positive(s.thickness_mm, "--thickness-mm");
      if (!(s.thickness_mm < s.semi_axes_mm.minCoeff())) {
        throw InputError(source, "--thickness-mm",
                         "must be less than the smallest semi-axis (" + num(s.semi_axes_mm.minCoeff()) + " mm), got " +
                             num(s.thickness_mm));
      }
      break;
    case PhantomKind::Torus:
      require_positive(s.major_mm, "--major-mm");
      require_positive(s.minor_mm, "--minor-mm");
      if (!(s.minor_mm < s.major_mm)) {
        throw InputError(source, "--minor-mm",
                         "must be less than --major-mm (" + num(s.major_mm) + " mm) so the torus has a hole, got " +
                             num(s.minor_mm));
      }
      break;
  }
}

double phantom_implicit_mm(const PhantomShape& s, const Eigen::Vector3d& p) {
  const Eigen::Vector3d q = p - s.centre_mm;
  switch (s.kind) {
    case PhantomKind::Sphere: return q.norm() - s.radius_mm;
    case PhantomKind::EllipsoidShell:
      return std::max(ellipsoid_implicit(q, s.semi_axes_mm), -ellipsoid_implicit(q, inner_semi_axes(s)));
    case PhantomKind::Torus: {
      const double rho = std::hypot(q.x(), q.y());
      return std::hypot(rho - s.major_mm, q.z()) - s.minor_mm;
    }
    case PhantomKind::BumpySphere: {
      const double len = q.norm();
      const Eigen::Vector3d u = len > 0.0 ? Eigen::Vector3d(q / len) : Eigen::Vector3d::UnitZ();
      return len - s.radius_mm * (1.0 + s.bump_amplitude * bump_from_direction(s, u));
    }
  }
  return std::numeric_limits<double>::quiet_NaN();
}

bool phantom_contains(const PhantomShape& shape, const Eigen::Vector3d& p_mm) { return phantom_implicit_mm(shape, p_mm) < 0.0; }

Eigen::Vector3d phantom_outward_normal(const PhantomShape& s, const Eigen::Vector3d& p) {
  const Eigen::Vector3d q = p - s.centre_mm;
  switch (s.kind) {
    case PhantomKind::Sphere: return normalized_or_z(q);
    case PhantomKind::EllipsoidShell: {
      const Eigen::Vector3d e_out = s.semi_axes_mm, e_in = inner_semi_axes(s);
      if (ellipsoid_implicit(q, e_out) >= -ellipsoid_implicit(q, e_in)) {
        return normalized_or_z(q.cwiseQuotient(e_out.cwiseProduct(e_out)));
      }
      return normalized_or_z(-q.cwiseQuotient(e_in.cwiseProduct(e_in)));
    }
    case PhantomKind::Torus: {
      const double rho = std::hypot(q.x(), q.y());
      if (!(rho > 0.0)) return Eigen::Vector3d::UnitZ();
      const Eigen::Vector3d ring(s.major_mm * q.x() / rho, s.major_mm * q.y() / rho, 0.0);
      return normalized_or_z(q - ring);
    }
    case PhantomKind::BumpySphere: {
      // grad(|q| - r(theta, phi)) = e_r - (r_theta e_theta + r_phi / sin(theta) e_phi) / |q|.
      const double len = q.norm();
      if (!(len > 0.0)) return Eigen::Vector3d::UnitZ();
      const double theta = std::atan2(std::hypot(q.x(), q.y()), q.z());
      const double phi = std::atan2(q.y(), q.x());
      const BumpDerivatives d = bump_derivatives(s, theta, phi);
      const double st = std::sin(theta), ct = std::cos(theta), sp = std::sin(phi), cp = std::cos(phi);
      const Eigen::Vector3d e_r(st * cp, st * sp, ct), e_theta(ct * cp, ct * sp, -st), e_phi(-sp, cp, 0.0);
      return normalized_or_z(e_r - (d.r_theta * e_theta + d.r_phi_by_sin * e_phi) / len);
    }
  }
  return Eigen::Vector3d::UnitZ();
}

Eigen::Vector3d bumpy_sphere_surface_point(const PhantomShape& s, double theta, double phi) {
  const double r = bump_derivatives(s, theta, phi).r;
  return s.centre_mm + r * Eigen::Vector3d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
}

double ellipsoid_surface_area_mm2(double a, double b, double c) {
  // x = (a sin t cos p, b sin t sin p, c cos t): |x_t x x_p| =
  // sin t sqrt(b^2 c^2 sin^2 t cos^2 p + a^2 c^2 sin^2 t sin^2 p + a^2 b^2 cos^2 t).
  const double bc2 = b * b * c * c, ac2 = a * a * c * c, ab2 = a * a * b * b;
  return integrate_over_sphere(
      [&](double t, double p) {
        const double st = std::sin(t), ct = std::cos(t), cp = std::cos(p), sp = std::sin(p);
        return st * std::sqrt(st * st * (bc2 * cp * cp + ac2 * sp * sp) + ab2 * ct * ct);
      },
      "ellipsoid area");
}

double phantom_volume_mm3(const PhantomShape& s) {
  switch (s.kind) {
    case PhantomKind::Sphere: return 4.0 / 3.0 * kPi * std::pow(s.radius_mm, 3);
    case PhantomKind::EllipsoidShell: return 4.0 / 3.0 * kPi * (s.semi_axes_mm.prod() - inner_semi_axes(s).prod());
    case PhantomKind::Torus: return 2.0 * kPi * kPi * s.major_mm * s.minor_mm * s.minor_mm;
    case PhantomKind::BumpySphere:
      // V = (1/3) int r^3 sin(theta) dtheta dphi for a star-shaped body.
      return integrate_over_sphere(
          [&](double t, double p) {
            const double r = bump_derivatives(s, t, p).r;
            return r * r * r * std::sin(t) / 3.0;
          },
          "bumpy sphere volume");
  }
  return std::numeric_limits<double>::quiet_NaN();
}

double phantom_area_mm2(const PhantomShape& s) {
  switch (s.kind) {
    case PhantomKind::Sphere: return 4.0 * kPi * s.radius_mm * s.radius_mm;
    case PhantomKind::EllipsoidShell: {
      const Eigen::Vector3d e = s.semi_axes_mm, i = inner_semi_axes(s);
      return ellipsoid_surface_area_mm2(e.x(), e.y(), e.z()) + ellipsoid_surface_area_mm2(i.x(), i.y(), i.z());
    }
    case PhantomKind::Torus: return 4.0 * kPi * kPi * s.major_mm * s.minor_mm;
    case PhantomKind::BumpySphere:
      // |x_theta x x_phi| = r sqrt((r^2 + r_theta^2) sin^2(theta) + r_phi^2).
      return integrate_over_sphere(
          [&](double t, double p) {
            const BumpDerivatives d = bump_derivatives(s, t, p);
            const double st = std::sin(t);
            const double r_phi = d.r_phi_by_sin * st;
            return d.r * std::sqrt((d.r * d.r + d.r_theta * d.r_theta) * st * st + r_phi * r_phi);
          },
          "bumpy sphere area");
  }
  return std::numeric_limits<double>::quiet_NaN();
}

Eigen::Vector3d phantom_half_extent_mm(const PhantomShape& s) {
  switch (s.kind) {
    case PhantomKind::Sphere: return Eigen::Vector3d::Constant(s.radius_mm);
    case PhantomKind::EllipsoidShell: return s.semi_axes_mm;
    case PhantomKind::Torus: return {s.major_mm + s.minor_mm, s.major_mm + s.minor_mm, s.minor_mm};
    case PhantomKind::BumpySphere: return Eigen::Vector3d::Constant(s.radius_mm * (1.0 + std::abs(s.bump_amplitude)));
  }
  return Eigen::Vector3d::Zero();
}

void validate_phantom_raster_options(const PhantomRasterOptions& o, const std::string& source) {
  for (int a = 0; a < 3; ++a) {
    if (!positive_finite(o.spacing_mm[a])) {
      throw InputError(source, "--spacing-mm",
                       "spacing along " + std::string(1, "xyz"[a]) + " must be a positive, finite number of mm, got " +
                           num(o.spacing_mm[a]));
    }
  }
  if (!(std::isfinite(o.margin_mm) && o.margin_mm >= 0.0)) {
    throw InputError(source, "--margin-mm", "must be a finite number of mm >= 0, got " + num(o.margin_mm));
  }
  if (o.supersample < 1 || o.supersample > 64) {
    throw InputError(source, "--supersample", "must be an integer in 1..64, got " + std::to_string(o.supersample));
  }
  if (!std::isfinite(o.hu_inside)) throw InputError(source, "--hu-inside", "must be a finite HU value");
  if (!std::isfinite(o.hu_outside)) throw InputError(source, "--hu-outside", "must be a finite HU value");
  if (o.hu_inside == o.hu_outside) {
    throw InputError(source, "--hu-inside", "must differ from --hu-outside, otherwise the object is invisible");
  }
  if (!(o.lattice_offset_voxels.cwiseAbs().maxCoeff() <= 0.5)) {
    throw InputError(source, "lattice_offset_voxels", "each component must lie in [-0.5, 0.5] voxels");
  }
}

ImageGeometry phantom_geometry(const PhantomShape& shape, const PhantomRasterOptions& options, const std::string& source) {
  validate_phantom_shape(shape, source);
  validate_phantom_raster_options(options, source);
  const Eigen::Vector3d h = phantom_half_extent_mm(shape);
  ImageGeometry g;
  for (int a = 0; a < 3; ++a) {
    const double half_count =
        std::ceil((h[a] + options.margin_mm) / options.spacing_mm[a] + std::abs(options.lattice_offset_voxels[a]));
    if (!(half_count < 1073741823.0)) {
      throw InputError(source, "--spacing-mm",
                       "spacing " + num(options.spacing_mm[a]) + " mm along " + std::string(1, "xyz"[a]) +
                           " gives more than 2^31 voxels across the phantom");
    }
    g.dims[a] = 2 * static_cast<int64_t>(half_count) + 1;
  }
  g.spacing = options.spacing_mm;
  const Eigen::Vector3d half_span(static_cast<double>(g.dims[0] - 1) / 2.0, static_cast<double>(g.dims[1] - 1) / 2.0,
                                  static_cast<double>(g.dims[2] - 1) / 2.0);
  g.origin = shape.centre_mm - options.spacing_mm.cwiseProduct(half_span + options.lattice_offset_voxels);
  g.direction.setIdentity();
  return g;
}

PhantomRaster rasterise_phantom(const PhantomShape& shape, const PhantomRasterOptions& options, const std::string& source) {
  const ImageGeometry g = phantom_geometry(shape, options, source);
  // dims are below 2^31 each (phantom_geometry), so nx * ny fits; the product with nz may not.
  const uint64_t plane = static_cast<uint64_t>(g.dims[0]) * static_cast<uint64_t>(g.dims[1]);
  if (plane > std::numeric_limits<uint64_t>::max() / static_cast<uint64_t>(g.dims[2])) {
    throw InputError(source, "--spacing-mm", "the phantom lattice has more voxels than can be counted; use a coarser spacing");
  }
  check_allocation(plane * static_cast<uint64_t>(g.dims[2]), sizeof(float) + sizeof(uint8_t), source, "--spacing-mm");

  PhantomRaster out;
  out.hu = Volume<float>(g, options.hu_outside);
  out.label = Volume<uint8_t>(g, 0);

  const int s = options.supersample;
  const int64_t s3 = static_cast<int64_t>(s) * s * s;
  std::vector<double> offset(static_cast<std::size_t>(s));
  for (int q = 0; q < s; ++q) offset[static_cast<std::size_t>(q)] = (q + 0.5) / s - 0.5;
  const Eigen::Vector3d sp = g.spacing;
  const double half_diagonal = 0.5 * sp.norm();
  const double hu_in = options.hu_inside, hu_out = options.hu_outside;
  std::vector<int64_t> slice_count(static_cast<std::size_t>(g.dims[2]), 0);

  // One z-slice per iteration: every voxel is written by exactly one thread, and the per-slice
  // integer sample counts are summed afterwards in slice order, so the result is deterministic.
#pragma omp parallel for schedule(dynamic, 1)
  for (int64_t k = 0; k < g.dims[2]; ++k) {
    int64_t count_in_slice = 0;
    for (int64_t j = 0; j < g.dims[1]; ++j) {
      for (int64_t i = 0; i < g.dims[0]; ++i) {
        const Eigen::Vector3d c = g.origin + sp.cwiseProduct(Eigen::Vector3d(static_cast<double>(i), static_cast<double>(j),
                                                                             static_cast<double>(k)));
        const int cls = classify_ball(shape, c, half_diagonal);
        int64_t inside = cls < 0 ? s3 : 0;
        if (cls == 0) {
          for (int qz = 0; qz < s; ++qz) {
            for (int qy = 0; qy < s; ++qy) {
              for (int qx = 0; qx < s; ++qx) {
                const Eigen::Vector3d p = c + sp.cwiseProduct(Eigen::Vector3d(offset[static_cast<std::size_t>(qx)],
                                                                              offset[static_cast<std::size_t>(qy)],
                                                                              offset[static_cast<std::size_t>(qz)]));
                inside += phantom_contains(shape, p) ? 1 : 0;
              }
            }
          }
        }
        count_in_slice += inside;
        const std::size_t n = static_cast<std::size_t>(g.flat_index(i, j, k));
        out.hu.voxels[n] = static_cast<float>(hu_out + (hu_in - hu_out) * static_cast<double>(inside) / static_cast<double>(s3));
        out.label.voxels[n] = 2 * inside >= s3 ? 1 : 0;
      }
    }
    slice_count[static_cast<std::size_t>(k)] = count_in_slice;
  }

  int64_t total = 0;
  for (int64_t c : slice_count) total += c;
  out.fraction_volume_mm3 = static_cast<double>(total) / static_cast<double>(s3) * g.voxel_volume_mm3();
  return out;
}

}  // namespace ctsurg
