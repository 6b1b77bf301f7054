#include "ctsurg/sim/springs/spring_calibration.h"

#include "ctsurg/core/error.h"

#include <Eigen/LU>

#include <cmath>

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

}  // namespace ctsurg::sim
