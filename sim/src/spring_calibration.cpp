#include "ctsurg/sim/spring_calibration.h"

#include "ctsurg/core/error.h"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

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
  const int64_t nn = mesh.node_count(), nt = mesh.tet_count();
  if (nn == 0 || nt == 0) throw InputError("tetmesh", "/tetmesh/tets", "empty mesh");
  std::vector<Real> rest(static_cast<size_t>(3 * nn));
  for (size_t i = 0; i < rest.size(); ++i) rest[i] = static_cast<Real>(mesh.nodes[i]);
  std::vector<double> mass(static_cast<size_t>(nn), 0.0);
  std::map<std::pair<int32_t, int32_t>, double> edge_volume;  // (i < j) -> sum of adjacent tet volumes
  for (int64_t t = 0; t < nt; ++t) {
    const int32_t* v = &mesh.tets[static_cast<size_t>(4 * t)];
    for (int a = 0; a < 4; ++a) {
      if (v[a] < 0 || v[a] >= nn) throw InputError("tetmesh", "/tetmesh/tets", "tet " + std::to_string(t) + " names a missing node");
    }
    const auto p = [&](int a, int c) { return mesh.nodes[static_cast<size_t>(3 * v[a] + c)]; };
    double e[3][3];
    for (int a = 0; a < 3; ++a) {
      for (int c = 0; c < 3; ++c) e[a][c] = p(a + 1, c) - p(0, c);
    }
    const double vol = (e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) - e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                        e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0])) / 6.0;
    if (!(vol > 0)) {
      throw InputError("tetmesh", "/tetmesh/tets", "tet " + std::to_string(t) + " has volume " + std::to_string(vol) +
                                                       " mm^3 (inverted or degenerate)");
    }
    for (int a = 0; a < 4; ++a) mass[static_cast<size_t>(v[a])] += material.density * vol / 4;
    for (int a = 0; a < 4; ++a) {
      for (int b = a + 1; b < 4; ++b) edge_volume[{std::min(v[a], v[b]), std::max(v[a], v[b])}] += vol;
    }
  }
  std::vector<Real> m(mass.size());
  for (size_t i = 0; i < mass.size(); ++i) {
    if (!(mass[i] > 0)) throw InputError("tetmesh", "/tetmesh/nodes", "node " + std::to_string(i) + " is in no tet");
    m[i] = static_cast<Real>(mass[i]);
  }
  std::vector<Spring> springs;
  springs.reserve(edge_volume.size());
  for (const auto& [edge, volume] : edge_volume) {
    double l2 = 0;
    for (int c = 0; c < 3; ++c) {
      const double d = mesh.nodes[static_cast<size_t>(3 * edge.second + c)] - mesh.nodes[static_cast<size_t>(3 * edge.first + c)];
      l2 += d * d;
    }
    springs.push_back({edge.first, edge.second, material.youngs_modulus_pa * volume / l2, std::sqrt(l2), 0.0});
  }
  return build_explicit_spring_model(rest, m, springs);
}

}  // namespace ctsurg::sim
