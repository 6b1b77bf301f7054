// The tetrahedral FEM as a simulation engine (base/simulation_engine.h): one model, its fixed nodes,
// the tools (fem_tools.h: grabs as prescribed displacements, point forces; probes as sphere contact),
// gravity, and the surface embedded in the tets, advanced by one of three integrators (fem_integrator.h,
// one file each: the engine holds the model, the tools' holds, the cuts, the removals and the surface;
// the integrator how it steps):
//
//   dynamic  explicit central differences (fem_explicit_dynamics.h); the tools are set before every
//            step (at its end time), and steps go in one call while no tool acts (on cuda: one launch
//            sequence and one wait instead of one per step). Its guard checks every step: step()
//            returns unstable, with the state before the failing step, when it fires.
//   static   a quasi-static sequence: each frame the equilibrium under that frame's grabs, forces and
//            gravity; the linear material by the factorised, condensed solver (fem_linear_static_solver.h:
//            one factorisation for the run, where the supports alone hold the model), the other laws
//            (and the linear one where a grab completes the supports) by Newton (fem_static_solver.h:
//            direct solves, the factor kept across frames), warm-started from the previous frame.
//            With local_region_mm: Newton only in a region of that geodesic radius around the tools'
//            nodes, the rest from the linear model factorised once (fem_local_region.h, the FEM paper's
//            section 5.2).
//   implicit backward Euler (fem_implicit_dynamics.h): Newton per step on the factorised tangent, steps
//            of a frame (dt default 1/60 s) whatever the tissue's stiffness; grabs and forces as the
//            explicit dynamics'.
//
// Backend::cuda runs the explicit dynamics and the iterative solves' conjugate gradients on the device;
// the factorisations stay on the CPU. Probes need the explicit dynamics (contact is part of no other
// solver); a blade separates linear tets and splits their nodes (fem_cutting.h: the solvers are rebuilt on
// the new mesh with the state carried over); a cautery (the remove primitive) takes the elements inside
// its tip at its rate under the explicit dynamics, linear tets, no contact and no blade beside it
// (fem_element_removal.h: the model rebuilt without them, nodes, state and step kept, the surface over
// them opened and closed over the crater). The engine sees each tool as the primitive it acts through,
// never as a tool kind. Restarts with a halved step are not offered (the implicit dynamics
// halves a failing step itself).
//
// Metrics beyond the engine's common ones: newton_iterations and cg_iterations of the last static
// solve, or the implicit dynamics' Newton iterations of all steps so far (cumulative: differences
// between frames are per frame); 0 for the explicit dynamics. With a local region also region_nodes,
// region_tets, interface_nodes (the last frame's region) and interface_residual (uN: the out-of-balance
// force at the interface, fem_local_region.h).
//
// Quadratic (10-node) tets run static and implicit; the surface follows them with the quadratic shape
// functions at each vertex's barycentric coordinates in its tet.
//
// Units: mm (local frame: LPS minus origin), s, g; forces uN, energies nJ.
#pragma once

#include "ctsurg/sim/base/backend.h"
#include "ctsurg/sim/base/particle_state.h"
#include "ctsurg/sim/base/simulation_engine.h"
#include "ctsurg/sim/fem/fem_cutting.h"
#include "ctsurg/sim/fem/fem_explicit_dynamics.h"
#include "ctsurg/sim/fem/fem_implicit_dynamics.h"
#include "ctsurg/sim/fem/fem_integrator.h"
#include "ctsurg/sim/fem/fem_linear_static_solver.h"
#include "ctsurg/sim/fem/fem_local_region.h"
#include "ctsurg/sim/fem/fem_model.h"
#include "ctsurg/sim/fem/fem_static_solver.h"
#include "ctsurg/sim/fem/fem_tools.h"
#include "ctsurg/sim/surface/embedded_surface.h"

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace ctsurg::sim {

// Explicit dynamics, static Newton per frame, or implicit (backward Euler) dynamics.
enum class FemSolver { dynamic, static_equilibrium, implicit };

// EngineOptions' dt, safety_factor and mass_damping are the dynamic solver's (FemDynamicsOptions).
struct FemEngineOptions : EngineOptions {
  FemSolver solver = FemSolver::dynamic;
  // The static solver's Newton solves (fem_static_solver.h: the linear solve, tolerances, limits);
  // threads and initial_displacements are the engine's.
  FemStaticOptions newton;
  FemImplicitScheme implicit_scheme = FemImplicitScheme::backward_euler;  // solver implicit (fem_implicit_dynamics.h)
  // Contact between the model's bodies and self-contact (fem_contact.h): solver dynamic, cpu.
  FemContactOptions contact;
  // Local region deformation (fem_local_region.h): the geodesic radius R (mm, > 0) of the region around
  // the tools' nodes that Newton solves with the model's law, the rest following the linear model
  // factorised once. solver static_equilibrium, linear tets, supports that hold the model alone.
  // Absent: the whole mesh by the model's law, as without it.
  std::optional<double> local_region_mm;
  int local_region_balance_iterations = 0;  // FemLocalRegionOptions::balance_iterations (0: Dirichlet coupling)
};

class FemEngine final : public SimulationEngine {
 public:
  // model (local frame, origin `origin` LPS mm); supports: the nodes held fixed and single fixed
  // components (rollers, symmetry planes: the static and implicit solvers only; its prescribed_* are not
  // used); the surface it carries (may be empty; its coupling names nodes). Throws
  // InputError(options.where, "fixed", ...) for a static solver without supports (the stiffness is
  // singular) or fixed components on the explicit dynamics, and as FemExplicitDynamics and
  // FemLinearStaticSolver for options or a backend they refuse.
  FemEngine(FemModel model, FemBoundaryConditions supports, EmbeddedSurface surface, const Vec3& origin,
            const FemEngineOptions& options, Backend backend = Backend::cpu);
  ~FemEngine() override;
  // Not copied or moved: the state lives where its solvers point.
  FemEngine(const FemEngine&) = delete;
  FemEngine& operator=(const FemEngine&) = delete;

  const FemModel& model() const { return model_; }
  const std::vector<double>& displacements() const { return u_; }  // #N x 3 mm, current after sync()

  EngineCounts counts() const override { return counts_; }
  const Vec3& origin() const override { return origin_; }
  const std::vector<double>& rest_positions() const override { return model_.nodes; }
  int32_t elements(std::vector<int32_t>& ids) const override {
    ids = model_.tets;
    return model_.nodes_per_element();
  }
  bool has_surface() const override { return !surface_.empty(); }
  std::vector<std::pair<std::string, std::string>> extra_metrics() const override;
  // Linear tets: a quarter of the mean edge (a cut is tested against every interior face); 0 for
  // quadratic ones (not cut).
  double blade_sweep_mm() const override;

  bool quasi_static() const override { return options_.solver == FemSolver::static_equilibrium; }
  double dt() const override;
  double time() const override;
  int64_t steps() const override { return steps_; }
  bool batches_steps() const override { return true; }
  StabilityReport step(const std::vector<ToolInput>& tools, int steps) override;
  void equilibrium(const std::vector<ToolInput>& tools, double time) override;

  void sync() override;
  void positions(std::vector<double>& xyz) const override;
  void surface_vertices(std::vector<float>& xyz) override;
  // The embedded surface's triangles; without a surface, the tet mesh's boundary faces over the nodes
  // (each body's own, a cut's lips included), so a model meshed without a surface still renders.
  const std::vector<uint32_t>& triangles() const override { return surface_.empty() ? boundary_triangles_ : surface_.triangles(); }
  const std::vector<Real>& surface_rest_vertices() const override { return surface_.rest_vertices(); }
  // The triangles closing a cautery's crater (a blade's cut is left open on the FEM).
  int64_t closing_triangles() const override { return surface_.fill_triangle_count(); }
  EngineMetrics metrics() const override;
  bool engaged(size_t tool) const override { return holds_.engaged(tool); }
  // A volume grip's load from its penalty; a node grab's from the static solve's reactions (the dynamic
  // solvers' node grabs: none measured); a force tool's the force it applies.
  bool tool_load(size_t tool, std::array<double, 6>& load) const override { return holds_.load(tool, u_, integrator_->reactions(), load); }
  // With local_region_mm: the last frame's region, per node (#N: kFemOutsideRegion, kFemInRegion,
  // kFemRegionInterface of fem_local_region.h); nullptr without.
  const std::vector<uint8_t>* local_region() const;
  // With local_region_mm: the last frame's region per surface vertex, each the largest flag of the nodes
  // it is tied to (its tet's corners: a vertex in a tet that touches the interface is drawn on it); the
  // node flags themselves without a surface. All 0 before the first solve. false without a local region.
  bool surface_vertex_region(std::vector<uint8_t>& flags) const override;

  StabilityReport check_stability() override { return {}; }  // the dynamics check every step
  bool can_restart() const override { return false; }
  void save_checkpoint() override;
  void restart_halved() override;

 private:
  void check_tools(const std::vector<ToolInput>& tools) const;
  void make_solvers();
  void apply_cuts(const std::vector<ToolInput>& tools);
  void split_nodes(const std::vector<int32_t>& tets, const std::vector<int32_t>& parents, const std::vector<ToolInput>& tools);
  void remove_tissue(const std::vector<ToolInput>& tools, int steps);

  FemModel model_;
  FemBoundaryConditions supports_;
  EmbeddedSurface surface_;
  Vec3 origin_;
  FemEngineOptions options_;
  Backend backend_;
  EngineCounts counts_;
  FemToolHolds holds_;
  std::vector<double> u_;           // #N x 3 mm
  std::vector<Real> rest_real_;     // #N x 3 mm, the rest positions as the surface kernel reads them
  ParticleState positions_;         // rest + u, for the surface
  // Quadratic tets: each surface vertex follows its tet's 10 nodes with the quadratic shape functions
  // at its barycentric coordinates (the surface's coupling gives the tet's corners and those).
  std::vector<int32_t> quadratic_nodes_;   // #V x 10
  std::vector<double> quadratic_weights_;  // #V x 10
  // How the model advances (fem_integrator.h: explicit, implicit or static, one file each), rebuilt
  // with the state carried over when a cut or a removal changes the mesh.
  std::unique_ptr<FemIntegrator> integrator_;
  int solves_ = 0, newton_ = 0, cg_ = 0;  // static frames solved; the Newton and CG iterations (metrics)
  double solver_error_mm_ = NAN;          // the last static frame's FemAdvance::solver_error_mm
  bool reports_solver_error() const;      // the metric solver_error_mm: static, quasi-Newton, no local region
  int64_t steps_ = 0;
  // Cutting (fem_cutting.h): the faces separated so far, and each surface vertex's tet and tie corners.
  std::unique_ptr<FemTetSeparation> separation_;
  std::vector<int32_t> surface_element_;  // #V
  std::vector<int32_t> surface_corner_;   // #V x 8: the tet corner (0..3) of each tie, -1 for none
  int64_t faces_cut_ = 0, triangles_removed_ = 0, nodes_split_ = 0;
  // Removal (fem_element_removal.h): each remove tool's budget (mm^3), and the volume taken so far.
  std::vector<double> removal_budget_;
  double removed_volume_ = 0;
  // With contact: each element's body at the start (the mesh's connected pieces; a cut later creates or
  // removes no element, so the bodies' volumes stay comparable), for the metrics body_volume_<b>.
  std::vector<int32_t> element_body_;
  std::vector<uint32_t> boundary_triangles_;  // without a surface: the corner tets' boundary (fem_boundary_faces)
  int32_t bodies_ = 0;
};

}  // namespace ctsurg::sim
