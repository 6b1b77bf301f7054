// A vessel as a simulation engine (base/simulation_engine.h): the medial-atom chain (vessel_chain.h)
// moved by backward Euler (vessel_dynamics.h) at a frame-rate step, its tube surface redrawn from the
// atoms each frame (vessel_skinning.h). The model's points (rest_positions, positions) are the atoms.
//
// Tools, acting on atoms:
//   grab   captures the free atoms inside its sphere when it first becomes active and holds them at
//          centre + R (offset at capture), R the turn of the tool's orientation since the capture
//          (a grab's keyframes may carry a rotation: a twist), until its window closes (then lets go
//          for good); the segments whose two atoms it holds keep their frames turned by R too. A
//          clamp is a grab that does not move (scenario.h). A grab that captures no atom is an
//          InputError naming the tool.
//   force  its total force (N) shared equally by the free atoms inside its sphere at its start.
//   probe  pushes atoms out of its sphere by the atom's radius (the tube, not the axis, touches it).
//   cut    a blade whose swept quad crosses a segment between two atoms cuts it: the stretch-shear
//          spring and its joints go, the chain splits there and the surface's rings either side are
//          capped (the quads between them go: the tube loses that segment's length, 1 atom spacing).
//          A blade that crosses the tube but not its axis cuts nothing. springs_cut counts segments.
//   instrument, suture: refused (InputError naming the tool).
// Fixed atoms (the scenario's fixed regions) never move; two neighbouring fixed atoms clamp their
// segment's frame (a built-in end), one alone is a pin.
//
// Stability: backward Euler does not blow up at any step, but the guard still checks (non-finite
// positions, an atom 10 m away, kinetic energy growing 1,000-fold between checks); restarts halve
// the step from the last checkpoint.
//
// Metrics beyond the common ones: chain_length (mm, the alive segments' current lengths), max_strain
// (the largest axial strain of a segment), newton_iterations (cumulative).
//
// CPU only: Backend::cuda is refused (InputError naming "backend").
// Units: mm (local frame: LPS minus origin), s, g; forces uN, energies nJ.
#pragma once

#include "ctsurg/sim/base/backend.h"
#include "ctsurg/sim/base/simulation_engine.h"
#include "ctsurg/sim/vessel/vessel_chain.h"
#include "ctsurg/sim/vessel/vessel_dynamics.h"
#include "ctsurg/sim/vessel/vessel_skinning.h"

#include <memory>
#include <string>
#include <vector>

namespace ctsurg::sim {

// EngineOptions' dt (0: a frame, 1/60 s), mass_damping and gravity are the dynamics'; safety_factor
// and threads are not used.
struct VesselEngineOptions : EngineOptions {
  int spokes = 16;                                 // vertices per ring, [3, 1024]
  VesselSkinning skinning = VesselSkinning::rmf;
  int max_newton_iterations = 6;                   // per step
};

class VesselEngine final : public SimulationEngine {
 public:
  // chain: in the local frame (origin `origin`, LPS mm); fixed_atoms: ids into its atoms.
  VesselEngine(VesselChain chain, const std::vector<int32_t>& fixed_atoms, const Vec3& origin, const VesselEngineOptions& options,
               Backend backend = Backend::cpu);
  VesselEngine(const VesselEngine&) = delete;
  VesselEngine& operator=(const VesselEngine&) = delete;

  const VesselChain& chain() const { return *chain_; }
  const VesselDynamics& dynamics() const { return *dynamics_; }

  EngineCounts counts() const override { return counts_; }
  const Vec3& origin() const override { return origin_; }
  const std::vector<double>& rest_positions() const override { return chain_->rest; }
  bool has_surface() const override { return true; }
  std::vector<std::pair<std::string, std::string>> extra_metrics() const override;
  double blade_sweep_mm() const override { return blade_sweep_; }

  bool quasi_static() const override { return false; }
  double dt() const override { return dynamics_->options().dt; }
  double time() const override { return time_; }
  int64_t steps() const override { return steps_; }
  StabilityReport step(const std::vector<ToolInput>& tools, int steps) override;
  void equilibrium(const std::vector<ToolInput>& tools, double time) override;

  void sync() override {}
  void positions(std::vector<double>& xyz) const override { xyz = dynamics_->x; }
  void surface_vertices(std::vector<float>& xyz) override;
  const std::vector<uint32_t>& triangles() const override { return skin_->triangles(); }
  const std::vector<Real>& surface_rest_vertices() const override { return rest_surface_; }
  EngineMetrics metrics() const override;
  bool engaged(size_t tool) const override;

  StabilityReport check_stability() override;
  bool can_restart() const override { return true; }
  void save_checkpoint() override;
  void restart_halved() override;

 private:
  struct Hold {
    bool released = false;
    std::vector<int32_t> atoms;        // grab: captured; force: loaded
    std::vector<double> offsets;       // grab: #atoms x 3, from the centre at capture
    std::vector<int32_t> segments;     // grab: segments with both atoms captured
    std::vector<Quaternion> frames;    // their frames at capture
    Quaternion orientation = kIdentityRotation;  // the tool's at capture
  };
  struct Checkpoint {
    std::vector<double> x, v, w;
    std::vector<Quaternion> q;
    std::vector<uint8_t> alive;
    double time = 0;
    int64_t steps = 0, cut = 0;
  };
  void apply_tools(const std::vector<ToolInput>& tools);
  void probe(const ToolInput& tool);
  bool cut(const ToolInput& tool);
  std::vector<int32_t> atoms_in_sphere(const Vec3& centre, double radius, bool free_only) const;
  void note(const std::string& text) const;

  std::unique_ptr<VesselChain> chain_;
  std::unique_ptr<VesselDynamics> dynamics_;
  std::unique_ptr<VesselSkin> skin_;
  Vec3 origin_;
  VesselEngineOptions options_;
  EngineCounts counts_;
  std::vector<Hold> holds_;
  std::vector<Real> rest_surface_;
  std::vector<uint8_t> alive_;
  double blade_sweep_ = 0;
  double time_ = 0;
  int64_t steps_ = 0, segments_cut_ = 0, newton_ = 0;
  double last_energy_ = 0;
  Checkpoint checkpoint_;
};

}  // namespace ctsurg::sim
