// The FEM benchmarks' models (bench_fem.cpp on the CPU, bench_fem_device.cpp on a CUDA device): the
// FEM paper's static experiment at its Table 2 sizes (Huang et al.: 1,018 .. 5,071 vertices) as a
// 20 mm cube of n^3 cells (Kuhn tets, (n + 1)^3 vertices), E = 30 kPa, nu = 0.45, bottom face fixed,
// the centre of the top face (radius 3.5 mm) grabbed `depth` mm down. Units: mm, Pa.
#pragma once

#include "ctsurg/sim/fem/fem_box_mesh.h"
#include "ctsurg/sim/fem/fem_model.h"
#include "ctsurg/sim/fem/fem_static_solver.h"

#include <cmath>
#include <map>
#include <memory>
#include <utility>

namespace ctsurg::sim::bench {

inline FemMaterial material(FemLaw model) {
  FemMaterial m;
  m.law = model;
  m.youngs_modulus = 3e4;
  m.poisson_ratio = 0.45;
  return m;
}

// The cube of n^3 cells, built once per (n, law) for the process.
inline const FemModel& cube(int n, FemLaw model) {
  static std::map<std::pair<int, int>, std::unique_ptr<FemModel>> models;
  auto& slot = models[{n, static_cast<int>(model)}];
  if (!slot) {
    const auto box = fem_box_mesh({n, n, n}, {20, 20, 20});
    slot = std::make_unique<FemModel>(build_fem_model(box.nodes, box.tets, material(model)));
  }
  return *slot;
}

inline FemBoundaryConditions cube_grab(const FemModel& m, double depth) {
  FemBoundaryConditions bc;
  for (int32_t i = 0; i < m.node_count(); ++i) {
    const double* p = &m.nodes[3 * i];
    if (p[2] == 0) bc.fixed_nodes.push_back(i);
    if (std::abs(p[2] - 20) < 1e-9 && std::hypot(p[0] - 10, p[1] - 10) <= 3.5) {
      bc.prescribed_nodes.push_back(i);
      bc.prescribed_displacements.insert(bc.prescribed_displacements.end(), {0.0, 0.0, -depth});
    }
  }
  return bc;
}

}  // namespace ctsurg::sim::bench
