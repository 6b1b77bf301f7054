// Small FEM models shared by the sim tests: boxes of Kuhn tets and node selection by a coordinate.
#pragma once

#include "ctsurg/sim/fem/fem_box_mesh.h"
#include "ctsurg/sim/fem/fem_model.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

namespace ctsurg::sim::test {

// A box of cells[0] x cells[1] x cells[2] cells (6 Kuhn tets each) spanning `size` mm from the origin,
// one material: E (Pa), nu, soft-tissue density.
inline FemModel fem_box_model(FemMaterialModel law, std::array<int, 3> cells, std::array<double, 3> size, double youngs_pa = 3e4,
                              double poisson = 0.45) {
  const auto box = fem_box_mesh(cells, size);
  FemMaterial m;
  m.model = law;
  m.youngs_modulus = youngs_pa;
  m.poisson_ratio = poisson;
  return build_fem_model(box.nodes, box.tets, m);
}

// The nodes whose coordinate `axis` (0 x, 1 y, 2 z) is `value` (to 1e-9 mm), increasing.
inline std::vector<int32_t> nodes_where(const FemModel& m, int axis, double value) {
  std::vector<int32_t> out;
  for (int32_t i = 0; i < m.node_count(); ++i)
    if (std::abs(m.nodes[3 * i + axis] - value) < 1e-9) out.push_back(i);
  return out;
}

}  // namespace ctsurg::sim::test
