// Removing tissue from an FEM model (the remove primitive of base/simulation_engine.h: a cautery): the
// elements whose centroid (at the current displacements) lies strictly inside a sphere, nearest its
// centre first (lower id on ties), as long as the next one's rest volume fits in a budget; then the
// model without them. The nodes stay (their ids are what the surface, the tools and the state name): a
// node no element uses any more is massless and held by every solver (FemModel::unused_nodes), and
// each kept element keeps its material. Linear tets (the corners are the element).
//
// Units: mm, mm^3; the model's local frame.
#pragma once

#include "ctsurg/sim/base/tool_shapes.h"
#include "ctsurg/sim/fem/fem_model.h"

#include <cstdint>
#include <vector>

namespace ctsurg::sim {

struct FemElementRemoval {
  std::vector<int32_t> elements;  // to remove, in the order taken (nearest first)
  double volume_mm3 = 0;          // their rest volume
  bool exhausted = false;         // no element left inside the sphere: the budget has nothing to spend on
};

// The elements to remove, spending *budget_mm3. u: #N x 3 mm. InputError("fem removal", ...) for a
// quadratic model or displacements of the wrong size.
FemElementRemoval fem_elements_in_sphere(const FemModel& model, const std::vector<double>& u, const Sphere& sphere,
                                         double* budget_mm3);

// The model without the elements flagged in `removed` (#T, 1 = remove); nodes, materials and the frame
// kept. InputError as build_fem_model (no element left: "tets").
FemModel fem_model_without(const FemModel& model, const std::vector<uint8_t>& removed);

}  // namespace ctsurg::sim
