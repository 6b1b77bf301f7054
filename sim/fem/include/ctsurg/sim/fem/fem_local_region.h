// Local region deformation (Huang et al., the FEM paper, section 5.2: "we restrict the deformation in a
// local level ... the Dijkstra algorithm is employed to calculate the shortest distance between mass
// points"): the full nonlinear FEM only in a region around where the tools act, the rest of the mesh
// carried by a cheaper global model, here the linear (small-strain) FEM of the whole mesh, whose
// stiffness is factorised once per run (fem_linear_static_solver.h). Each solve (a quasi-static frame):
//
//   1. global   the linear solve of the whole mesh under the frame's grabs, forces and gravity, with the
//               supports (FemLinearStaticSolver: the supports alone must hold the model);
//   2. region   the nodes within a geodesic distance R (mm) of the seeds (the nodes the tools hold or
//               load), by Dijkstra over the mesh's edges at their rest lengths from all seeds at once: the
//               union of one ball per tool, merged where they overlap. Geodesic rather than Euclidean,
//               as the paper does: the region follows the material, so it does not jump across a gap or
//               a fold to tissue that is near in space but far through the mesh (a kidney's hilum, the
//               two sides of a cut); and in rest lengths, so a grab's region is a fixed piece of tissue
//               that moves with it. The region's tets are those with ALL four corners in it (the region
//               never reaches beyond R); its pieces with no free node, or fewer than 3 held nodes, are
//               dropped (nothing to solve, or a piece that could turn about its few ties);
//   3. coupling the nonlinear Newton solve (fem_static_solver.h, the model's law) on the region's tets
//               alone, with the interface nodes (region nodes that also belong to a tet outside it) held
//               at the global solution's displacement: Dirichlet coupling, the displacement continuous
//               across the interface, the forces not balanced there. The out-of-balance force of the
//               composed field at the interface nodes, f_int + f_ext with the region's tets by the law and
//               the outside ones linear (the two models the field is made of), is measured and reported
//               (interface_residual). Warm-started from `initial` (the previous frame); the region's Newton solver (pattern, analysis, factor) is kept while the region's
//               tets stay the same (a grab's region does, until a tool captures or releases);
//   4. result   the region's nodes from 3, every other node from 1.
//   5. balance  (optional, balance_iterations > 0) the Dirichlet coupling leaves the interface out of
//               balance: the region's tets pull on it with their law's forces, the global model's
//               solution assumed linear ones. Each balance iteration solves the global linear model
//               again with the region's tets' force difference f_law(u) - f_linear(u) added to the loads
//               of their nodes (one more back-substitution with the kept factor), then 3 again with the
//               new interface displacements, until the interface moves less than
//               balance_tolerance_mm. A fixed point is the hybrid model's equilibrium: the region's tets
//               by their law, the others linear, the forces balanced at the interface (a block
//               Gauss-Seidel, Dirichlet-Neumann iteration with the linear stiffness as the global
//               preconditioner: converges linearly while the region's law stays near the linear one).
//               The outside is still linear: far-field errors of the linear model (a large rotation of
//               the whole organ) stay.
//
// With R covering the whole mesh there is no interface and the result is the full nonlinear solve; as
// the load goes to zero it is the linear one. In between, the error is that of the linear model outside
// the region (and at the interface), which shrinks as R grows (docs/fem.md, "Local region", has the
// numbers). Linear (4-node) tets only.
//
// Units: mm (the model's frame), forces uN (g mm/s^2), arrays #N x 3 row-major.
#pragma once

#include "ctsurg/sim/base/backend.h"
#include "ctsurg/sim/fem/fem_linear_static_solver.h"
#include "ctsurg/sim/fem/fem_model.h"
#include "ctsurg/sim/fem/fem_static_solver.h"

#include <cstdint>
#include <memory>
#include <vector>

namespace ctsurg::sim {

// The geodesic distance (mm) of every node from the nearest of `seeds` through the mesh's edges at
// their rest lengths (Dijkstra from all seeds at once), searched up to limit_mm: #N, +infinity beyond
// the limit and for nodes no tet uses. seeds: node ids (repeats allowed). Throws
// InputError("fem local region", "seeds", ...) for an id out of range.
std::vector<double> fem_geodesic_distances(const FemModel& model, const std::vector<int32_t>& seeds, double limit_mm);

struct FemLocalRegionOptions {
  double radius_mm = 0;             // R, > 0 and finite
  FemStaticOptions newton;          // the region's Newton solves (initial_displacements unused: see solve)
  FemLinearSolverOptions linear;    // the global linear solve
  // Balance iterations (see 5 above): 0 = the Dirichlet coupling alone.
  int balance_iterations = 0;       // >= 0
  double balance_tolerance_mm = 1e-3;  // stop when no interface component moved more than this (> 0)
};

// Node flags of node_region().
enum : uint8_t { kFemOutsideRegion = 0, kFemInRegion = 1, kFemRegionInterface = 2 };

struct FemLocalRegionReport {
  int32_t region_nodes = 0;        // nodes of the region's tets (interface included)
  int32_t region_tets = 0;
  int32_t interface_nodes = 0;     // region nodes held at the global solution
  double interface_residual = 0;   // uN: || f_int + f_ext || (2-norm) at the composed field over the interface
                                   // nodes (supports and tool nodes apart; see 3 above)
  double tool_load = 0;            // uN: | sum of the grab reactions and tool forces |, the scale of the above
  int balance_iterations = 0;      // balance iterations taken (global re-solves)
  double balance_change_mm = 0;    // the last one's largest interface change
  bool rebuilt = false;            // the region's tets changed: its model and Newton solver were rebuilt
  double global_seconds = 0;       // step 1
  double region_seconds = 0;       // steps 2-4 (selection, rebuild, Newton, the residual)
};

class FemLocalRegionSolver {
 public:
  // model: linear tets, any law (the region's); supports: fixed nodes and components, which alone must
  // hold the model (the global solve's condensation). Throws InputError("fem local region",
  // "radius_mm" | "order" | "balance_iterations" | "balance_tolerance_mm", ...) and as FemLinearStaticSolver (its "boundary conditions" when the
  // supports leave a rigid motion free). The model must outlive the solver.
  FemLocalRegionSolver(const FemModel& model, const FemBoundaryConditions& supports, const FemLocalRegionOptions& options,
                       Backend backend = Backend::cpu);
  ~FemLocalRegionSolver();
  FemLocalRegionSolver(const FemLocalRegionSolver&) = delete;
  FemLocalRegionSolver& operator=(const FemLocalRegionSolver&) = delete;

  // The composed equilibrium (steps 1-4 above) with `prescribed_nodes` (#G, not supported) held at
  // `prescribed_displacements` (#G x 3 mm) under `loads`; the region grows from `seeds` (node ids: the
  // tools' captured and loaded nodes; none: no region, the global solution everywhere). initial: #N x 3
  // mm, the region's Newton warm start (the previous frame), or nullptr (load stepping from rest).
  // The result's report: the region's Newton iterations and CG iterations, converged = both solves
  // converged, seconds = the whole call; reactions at the held nodes (the region's where it holds them,
  // else the global solve's). Throws as FemLinearStaticSolver::solve and FemStaticSolver::solve.
  // seed_radii (optional, #seeds mm, > 0): each seed's own radius (a tool's region: a node is in the
  // region when it is within the radius of some seed); nullptr: options.radius_mm for every seed.
  FemStaticResult solve(const std::vector<int32_t>& prescribed_nodes, const std::vector<double>& prescribed_displacements,
                        const FemLoads& loads, const std::vector<int32_t>& seeds, const std::vector<double>* initial = nullptr,
                        const std::vector<double>* seed_radii = nullptr);

  const FemLocalRegionReport& report() const;                 // of the last solve
  const std::vector<uint8_t>& node_region() const;            // #N flags of the last solve (kFem*Region*)
  const FemLinearSolverStats& linear_stats() const;           // the global factorisation

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ctsurg::sim
