#include "ctsurg/sim/springs/spring_calibration.h"

#include "ctsurg/core/error.h"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <string>

namespace ctsurg::sim {

double grid_spring_stiffness(double youngs_modulus_pa, const ImageGeometry& lattice) {
  const double h = std::cbrt(std::abs(lattice.index_to_world_matrix().determinant()));
  return 0.4 * youngs_modulus_pa * h;
}

SpringGridMaterial calibrated_grid_material(const Material& material, const ImageGeometry& lattice,
                                            bool mass_from_fraction) {
  validate_material(material);
  SpringGridMaterial m;
  m.density = material.density;
  m.face_stiffness = m.edge_stiffness = grid_spring_stiffness(material.youngs_modulus_pa, lattice);
  m.mass_from_fraction = mass_from_fraction;
  return m;
}

ExplicitSpringModel calibrated_tet_spring_model(const TetMesh& mesh, const Material& material) {
  validate_material(material);
  const double e = material.youngs_modulus_pa;
  return explicit_model_from_tet_mesh(mesh, material.density,
                                      [e](double volume, double length) { return e * volume / (length * length); });
}

namespace {

// Checks every material and that `of` (#count) indexes them.
void check_material_indices(const std::vector<Material>& materials, const std::vector<int32_t>& of, std::size_t count,
                            const char* element) {
  if (materials.empty()) throw InputError("materials", "materials", "none given");
  for (const Material& m : materials) validate_material(m);
  if (of.size() != count) {
    throw InputError("materials", std::string(element) + "_material",
                     std::to_string(of.size()) + " entries for " + std::to_string(count) + " " + element + "s");
  }
  for (std::size_t e = 0; e < of.size(); ++e) {
    if (of[e] < 0 || static_cast<std::size_t>(of[e]) >= materials.size()) {
      throw InputError("materials", std::string(element) + "_material",
                       std::string(element) + " " + std::to_string(e) + " names material " + std::to_string(of[e]) + " of " +
                           std::to_string(materials.size()));
    }
  }
}

}  // namespace

ExplicitSpringModel calibrated_tet_spring_model(const TetMesh& mesh, const std::vector<Material>& materials,
                                                const std::vector<int32_t>& tet_material) {
  check_material_indices(materials, tet_material, static_cast<std::size_t>(std::max<int64_t>(mesh.tet_count(), 0)), "tet");
  std::vector<double> density(tet_material.size()), modulus(tet_material.size());
  for (std::size_t t = 0; t < tet_material.size(); ++t) {
    const Material& m = materials[static_cast<std::size_t>(tet_material[t])];
    density[t] = m.density;
    modulus[t] = m.youngs_modulus_pa;
  }
  return explicit_model_from_tet_mesh(mesh, density, modulus,
                                      [](double weighted_volume, double length) { return weighted_volume / (length * length); });
}

ExplicitSpringModel calibrated_grid_spring_model(const SpringGridModel& grid, const std::vector<Material>& materials,
                                                 const std::vector<int32_t>& particle_material, double grid_density) {
  const int64_t n = grid.particle_count();
  check_material_indices(materials, particle_material, static_cast<std::size_t>(n), "particle");
  if (!(std::isfinite(grid_density) && grid_density > 0)) throw InputError("materials", "grid_density", "must be finite and > 0");
  std::vector<Real> mass(grid.mass.size());
  for (int64_t p = 0; p < n; ++p) {
    const double density = materials[static_cast<std::size_t>(particle_material[static_cast<std::size_t>(p)])].density;
    mass[static_cast<std::size_t>(p)] = static_cast<Real>(grid.mass[static_cast<std::size_t>(p)] * (density / grid_density));
  }
  std::vector<Spring> springs;
  springs.reserve(static_cast<std::size_t>(grid.spring_count()));
  for (int64_t a = 0; a < n; ++a) {
    const double ea = materials[static_cast<std::size_t>(particle_material[static_cast<std::size_t>(a)])].youngs_modulus_pa;
    for (int d = 0; d < kGridDirections; ++d) {
      if ((grid.spring_mask[static_cast<std::size_t>(a)] >> d & 1u) == 0) continue;
      const int32_t b = grid.neighbours[static_cast<std::size_t>(d * n + a)];
      if (b <= a) continue;
      const double eb = materials[static_cast<std::size_t>(particle_material[static_cast<std::size_t>(b)])].youngs_modulus_pa;
      const double series = 2.0 * ea * eb / (ea + eb);
      springs.push_back({static_cast<int32_t>(a), b, grid_spring_stiffness(series, grid.lattice), grid.rest_length[d], grid.damping[d]});
    }
  }
  return build_explicit_spring_model(grid.rest_positions, mass, springs);
}

}  // namespace ctsurg::sim
