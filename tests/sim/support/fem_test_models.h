// Small FEM models shared by the sim tests: materials, boxes of Kuhn tets, node selection by a
// coordinate, and the largest value or difference of displacement arrays.
#pragma once

#include "ctsurg/sim/fem/fem_box_mesh.h"
#include "ctsurg/sim/fem/fem_model.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace ctsurg::sim::test {

// A box of cells[0] x cells[1] x cells[2] cells (6 Kuhn tets each) spanning `size` mm from the origin,
// one material: E (Pa), nu, soft-tissue density.
// A material of the law, E (Pa) and nu, soft-tissue density.
inline FemMaterial fem_material(FemLaw law, double youngs_pa = 3e4, double poisson = 0.3) {
  FemMaterial m;
  m.law = law;
  m.youngs_modulus = youngs_pa;
  m.poisson_ratio = poisson;
  return m;
}

inline FemModel fem_box_model(FemLaw law, std::array<int, 3> cells, std::array<double, 3> size, double youngs_pa = 3e4,
                              double poisson = 0.45) {
  const auto box = fem_box_mesh(cells, size);
  return build_fem_model(box.nodes, box.tets, fem_material(law, youngs_pa, poisson));
}

// The nodes whose coordinate `axis` (0 x, 1 y, 2 z) is `value` (to 1e-9 mm), increasing.
inline std::vector<int32_t> nodes_where(const FemModel& m, int axis, double value) {
  std::vector<int32_t> out;
  for (int32_t i = 0; i < m.node_count(); ++i)
    if (std::abs(m.nodes[3 * i + axis] - value) < 1e-9) out.push_back(i);
  return out;
}

// The largest |v_k|.
inline double max_abs(const std::vector<double>& v) {
  double m = 0;
  for (const double x : v) m = std::max(m, std::abs(x));
  return m;
}

// The largest |a_k - b_k| (float or double arrays); infinity when the sizes differ.
template <class T>
double max_abs_difference(const std::vector<T>& a, const std::vector<T>& b) {
  if (a.size() != b.size()) return HUGE_VAL;
  double m = 0;
  for (std::size_t k = 0; k < a.size(); ++k) m = std::max(m, std::abs(double(a[k]) - double(b[k])));
  return m;
}

}  // namespace ctsurg::sim::test
