#include "ctsurg/sim/vessel/vessel_calibration.h"

#include "ctsurg/core/error.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace ctsurg::sim {

TubeSection tube_section(double radius_mm, double thickness_mm) {
  const double outer = radius_mm + 0.5 * thickness_mm;
  const double inner = std::max(0.0, radius_mm - 0.5 * thickness_mm);
  const double pi = std::numbers::pi;
  TubeSection s;
  s.area = pi * (outer * outer - inner * inner);
  s.second_moment = pi / 4 * (std::pow(outer, 4) - std::pow(inner, 4));
  s.polar_moment = 2 * s.second_moment;
  s.lumen_area = pi * inner * inner;
  return s;
}

void validate_vessel_wall(const VesselWall& w, const std::string& where) {
  if (!(std::isfinite(w.youngs_modulus_pa) && w.youngs_modulus_pa >= 1 && w.youngs_modulus_pa <= 1e11))
    throw InputError(where, "material.youngs_modulus_pa", "must be in [1, 1e11] Pa");
  if (!(std::isfinite(w.poisson_ratio) && w.poisson_ratio > -1 && w.poisson_ratio < 0.5))
    throw InputError(where, "material.poisson_ratio", "must be in (-1, 0.5)");
  if (!(std::isfinite(w.thickness_mm) && w.thickness_mm > 0 && w.thickness_mm <= 50))
    throw InputError(where, "vessel.wall_thickness_mm", "must be in (0, 50] mm");
  if (!(std::isfinite(w.density) && w.density > 0)) throw InputError(where, "material.density_g_per_cm3", "must be > 0");
  if (!(std::isfinite(w.blood_density) && w.blood_density > 0)) throw InputError(where, "vessel.blood_density_g_per_cm3", "must be > 0");
}

ChainStiffness tube_stiffness(const VesselWall& w, double radius_mm) {
  const TubeSection s = tube_section(radius_mm, w.thickness_mm);
  const double nu = w.poisson_ratio;
  const double g = w.youngs_modulus_pa / (2 * (1 + nu));
  const double kappa = 2 * (1 + nu) / (4 + 3 * nu);
  ChainStiffness k;
  k.stretch = w.youngs_modulus_pa * s.area;
  k.shear = kappa * g * s.area;
  k.bending = w.youngs_modulus_pa * s.second_moment;
  k.torsion = g * s.polar_moment;
  k.mass_per_mm = w.density * s.area + (w.blood_filled ? w.blood_density * s.lumen_area : 0.0);
  k.rotational_inertia_per_mm = w.density * s.polar_moment;
  return k;
}

}  // namespace ctsurg::sim
