#include "ctsurg/sim/fem/fem_forces.h"

#include "fem_cpu_kernels.h"
#include "fem_element_view.h"

#include "ctsurg/core/error.h"

#include <cmath>
#include <string>

namespace ctsurg::sim {
namespace {

void check_displacements(const FemModel& model, const std::vector<double>& u, const char* where) {
  if (u.size() != 3 * static_cast<std::size_t>(model.node_count()))
    throw InputError(where, "displacements", "expected #N x 3 = " + std::to_string(3 * model.node_count()) +
                                                 " values, got " + std::to_string(u.size()));
}

void check_tet(const FemModel& model, int32_t e, const char* where) {
  if (e < 0 || e >= model.tet_count()) throw InputError(where, "tet", "id " + std::to_string(e) + " out of range");
  if (model.order != 1) throw InputError(where, "order", "per-element values are of linear tets only (F varies in a quadratic one)");
}

void element_displacements(const FemModel& model, int32_t e, const std::vector<double>& u, double* ue) {
  for (int a = 0; a < 4; ++a)
    for (int c = 0; c < 3; ++c) ue[3 * a + c] = u[3 * model.tets[4 * e + a] + c];
}

}  // namespace

int32_t fem_internal_forces(const FemModel& model, const std::vector<double>& displacements, std::vector<double>& forces,
                            int threads) {
  check_displacements(model, displacements, "fem forces");
  const FemElementView<double> el = fem_element_view(model);
  std::vector<double> corner(3 * static_cast<std::size_t>(model.nodes_per_element()) * static_cast<std::size_t>(model.tet_count()));
  forces.resize(displacements.size());
  return cpu::fem_forces(el, model.node_offsets.data(), model.node_corners.data(), model.node_count(),
                         displacements.data(), corner.data(), forces.data(), threads);
}

double fem_strain_energy(const FemModel& model, const std::vector<double>& displacements) {
  check_displacements(model, displacements, "fem strain energy");
  double energy = 0;
  const FemElementView<double> el = fem_element_view(model);
  if (model.order == 2) {
    for (int32_t e = 0; e < model.tet_count(); ++e) {
      double ue[30];
      for (int a = 0; a < 10; ++a)
        for (int c = 0; c < 3; ++c) ue[3 * a + c] = displacements[3 * static_cast<std::size_t>(model.tets[10 * static_cast<std::size_t>(e) + a]) + c];
      const double w = fem_quadratic_element_energy(el.material(e), ue, &model.dm_inverse[9 * e], model.rest_volume[e]);
      if (w >= 1e30) return HUGE_VAL;
      energy += w;
    }
    return energy;
  }
  for (int32_t e = 0; e < model.tet_count(); ++e) {
    double ue[12], F[9];
    element_displacements(model, e, displacements, ue);
    fem_deformation_gradient(ue, &model.dm_inverse[9 * e], F);
    if (fem_law_traits(el.material(e).law).needs_positive_j && !(det3(F) > 0)) return HUGE_VAL;
    energy += model.rest_volume[e] * fem_energy_density(el.material(e), F);
  }
  return energy;
}

std::array<double, 9> fem_deformation_gradient(const FemModel& model, int32_t e, const std::vector<double>& displacements) {
  check_displacements(model, displacements, "fem deformation gradient");
  check_tet(model, e, "fem deformation gradient");
  double ue[12];
  element_displacements(model, e, displacements, ue);
  std::array<double, 9> F{};
  fem_deformation_gradient(ue, &model.dm_inverse[9 * e], F.data());
  return F;
}

std::array<double, 9> fem_element_stress(const FemModel& model, int32_t e, const std::vector<double>& displacements) {
  const auto F = fem_deformation_gradient(model, e, displacements);
  std::array<double, 9> P{};
  fem_first_piola(fem_element_law(model, e), F.data(), P.data());
  return P;
}

std::array<double, 144> fem_element_stiffness(const FemModel& model, int32_t e, const std::vector<double>& displacements) {
  check_displacements(model, displacements, "fem element stiffness");
  check_tet(model, e, "fem element stiffness");
  double ue[12];
  element_displacements(model, e, displacements, ue);
  std::array<double, 144> K{};
  fem_element_stiffness(fem_element_law(model, e), ue, &model.dm_inverse[9 * e], model.rest_volume[e], K.data());
  return K;
}

}  // namespace ctsurg::sim
