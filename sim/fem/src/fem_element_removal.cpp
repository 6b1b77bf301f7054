#include "ctsurg/sim/fem/fem_element_removal.h"

#include "ctsurg/core/error.h"

#include <algorithm>
#include <string>
#include <utility>

namespace ctsurg::sim {

FemElementRemoval fem_elements_in_sphere(const FemModel& model, const std::vector<double>& u, const Sphere& sphere,
                                         double* budget_mm3) {
  if (model.order != 1) throw InputError("fem removal", "elements", "removing elements needs linear (4-node) tets");
  if (u.size() != model.nodes.size()) throw InputError("fem removal", "displacements", "expected #N x 3");
  std::vector<std::pair<double, int32_t>> inside;
  const double r2 = sphere.radius * sphere.radius;
  for (int32_t e = 0; e < model.tet_count(); ++e) {
    double c[3] = {0, 0, 0};
    for (size_t a = 0; a < 4; ++a) {
      const size_t n = 3 * static_cast<size_t>(model.tets[4 * static_cast<size_t>(e) + a]);
      for (size_t k = 0; k < 3; ++k) c[k] += 0.25 * (model.nodes[n + k] + u[n + k]);
    }
    const double d2 = (c[0] - sphere.centre[0]) * (c[0] - sphere.centre[0]) + (c[1] - sphere.centre[1]) * (c[1] - sphere.centre[1]) +
                      (c[2] - sphere.centre[2]) * (c[2] - sphere.centre[2]);
    if (d2 < r2) inside.emplace_back(d2, e);
  }
  std::sort(inside.begin(), inside.end());
  FemElementRemoval r;
  size_t k = 0;
  for (; k < inside.size(); ++k) {
    const double volume = model.rest_volume[static_cast<size_t>(inside[k].second)];
    if (volume > *budget_mm3) break;
    *budget_mm3 -= volume;
    r.volume_mm3 += volume;
    r.elements.push_back(inside[k].second);
  }
  r.exhausted = k == inside.size();
  return r;
}

FemModel fem_model_without(const FemModel& model, const std::vector<uint8_t>& removed) {
  if (removed.size() != static_cast<size_t>(model.tet_count())) throw InputError("fem removal", "elements", "expected one flag per element");
  const size_t npe = static_cast<size_t>(model.nodes_per_element());
  std::vector<int32_t> tets, material;
  tets.reserve(model.tets.size());
  for (int32_t e = 0; e < model.tet_count(); ++e) {
    if (removed[static_cast<size_t>(e)]) continue;
    tets.insert(tets.end(), model.tets.begin() + static_cast<std::ptrdiff_t>(npe * static_cast<size_t>(e)),
                model.tets.begin() + static_cast<std::ptrdiff_t>(npe * static_cast<size_t>(e + 1)));
    if (!model.element_material.empty()) material.push_back(model.element_material[static_cast<size_t>(e)]);
  }
  FemModel m = build_fem_model(model.nodes, tets, model.materials, material);
  m.frame_origin = model.frame_origin;
  return m;
}

}  // namespace ctsurg::sim
