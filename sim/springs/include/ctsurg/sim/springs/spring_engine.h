// The spring-mass models as a simulation engine (base/simulation_engine.h): the implicit 18-neighbour
// grid or explicit springs, stepped with Verlet (spring_mass_step.h) on the CPU or, with
// Backend::cuda, on a CUDA device (DeviceSimulation, device_simulation.h), with the same kernels.
//
// Per step, in order: the spring forces and the Verlet update; then, at the new time, each tool in
// tool order (Mosegaard & Sorensen 2005, section 2.7: tools act after the integration and override
// it): a grab's particles are set to its centre plus their offsets (captured at the first step it is
// active: the particles strictly inside its sphere; released when it stops), a probe pushes the free
// particles out of its sphere, a force adds (F / n) / m dt^2 to each of the n free particles inside its
// sphere at its start (the same update as the force inside the step), a suture's stitches pull their
// particles (suture.h: placed when it starts, tightened over its window, kept after), a blade cuts
// every spring and surface triangle its edge crossed along each sweep (two triangles per sweep:
// tool_shapes.h), and a cautery removes the particles inside its tip at its rate, nearest first
// (particle_removal.h), with the surface triangles over them; with the surface's close_cuts, the holes
// the sweep or the crater left are then closed (hole_filling.h). The engine sees each tool as the
// primitive it acts through (base/simulation_engine.h), never as a tool kind.
//
// Stability: check_stability() runs the guard (stability.h) on the state; energy growth is not
// counted over an interval in which a tool acted. On the CPU the engine restarts from its last
// checkpoint with half the step (the Verlet velocities kept: previous = x - (x - previous) / 2). On a
// device it does not restart, and force tools are refused (a force changes the state on the host
// every step).
//
// The device engine keeps the state on the device: sync() copies the positions and the spring
// presence back (output frames, stability checks and cuts call it). Grabs are held on the device
// (DeviceSimulation's handles) and placed after every step there. Unverified on a GPU in this
// repository's CI (docs/gpu.md).
//
// Units: mm (local frame: LPS minus origin), s, g.
#pragma once

#include "ctsurg/sim/base/backend.h"
#include "ctsurg/sim/base/particle_state.h"
#include "ctsurg/sim/base/simulation_engine.h"
#include "ctsurg/sim/springs/explicit_spring_model.h"
#include "ctsurg/sim/springs/sphere_tools.h"
#include "ctsurg/sim/springs/spring_grid_model.h"
#include "ctsurg/sim/springs/spring_mass_step.h"
#include "ctsurg/sim/springs/stability.h"
#include "ctsurg/sim/springs/suture.h"
#include "ctsurg/sim/surface/embedded_surface.h"

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace ctsurg::sim {

using SpringModel = std::variant<SpringGridModel, ExplicitSpringModel>;

class SpringStepper;  // where the state is stepped (src/spring_stepper.h: the CPU or a CUDA device)

class SpringEngine final : public SimulationEngine {
 public:
  // model and state (its particles, with the fixed ones fixed: inverse mass 0) in the local frame whose
  // origin is `origin` (LPS mm); surface: the surface the model carries (may be empty). options.dt: 0 =
  // safety_factor x the critical step (stability.h); options.mass_damping alpha gives the Verlet
  // damping min(0.99, alpha dt) per step. Throws
  // InputError as critical_time_step for a model without springs, as step() for parameters out of
  // range, and as DeviceSimulation for cuda where it cannot run.
  SpringEngine(SpringModel model, ParticleState state, EmbeddedSurface surface, const Vec3& origin,
               const EngineOptions& options, Backend backend = Backend::cpu);
  ~SpringEngine() override;
  // Not copied or moved: the state lives where its solvers point.
  SpringEngine(const SpringEngine&) = delete;
  SpringEngine& operator=(const SpringEngine&) = delete;

  const SpringModel& model() const { return model_; }
  // Holds single components (3 particle + axis: rollers, symmetry planes) at their rest value: after
  // every step the coordinate and its previous value are set back to rest (no velocity along it), as
  // the tools overwrite the integration. CPU only (InputError on a device).
  void hold_components(std::vector<int32_t> components);
  const ParticleState& state() const { return state_; }  // the host's copy (current after sync())

  EngineCounts counts() const override { return counts_; }
  const Vec3& origin() const override { return origin_; }
  const std::vector<double>& rest_positions() const override { return rest_; }
  bool has_surface() const override { return !surface_.empty(); }
  double blade_sweep_mm() const override { return blade_sweep_mm_; }

  bool quasi_static() const override { return false; }
  double dt() const override { return params_.dt; }
  double time() const override { return time_; }
  int64_t steps() const override { return steps_; }
  StabilityReport step(const std::vector<ToolInput>& tools, int steps) override;
  void equilibrium(const std::vector<ToolInput>& tools, double time) override;

  void sync() override;
  void positions(std::vector<double>& xyz) const override;
  void surface_vertices(std::vector<float>& xyz) override;
  const std::vector<uint32_t>& triangles() const override { return surface_.triangles(); }
  int64_t closing_triangles() const override { return surface_.fill_triangle_count(); }
  const std::vector<Real>& surface_rest_vertices() const override { return surface_.rest_vertices(); }
  EngineMetrics metrics() const override;
  bool engaged(size_t tool) const override;
  std::vector<std::array<Vec3, 2>> stitches(size_t tool) const override;
  // The stiffness a stitch gets per unit of stitch_stiffness_ratio: the model's stiffest spring, g/s^2.
  double stitch_unit_stiffness() const { return stitch_unit_stiffness_; }

  StabilityReport check_stability() override;
  bool can_restart() const override;
  void save_checkpoint() override;
  void restart_halved() override;

 private:
  // What a tool holds (by tool index).
  struct Hold {
    std::optional<Grab> grab;     // grab: the captured particles
    int handle = -1;              // grab: the stepper's name for it (a device holds several)
    std::vector<int32_t> loaded;  // force: the free particles sharing it
    bool released = false;        // let go, for good
    std::vector<Stitch> stitches; // stitch: placed when it starts
    SutureSchedule schedule;      // stitch: how they tighten
    double removal_budget_mm3 = 0;  // remove: the volume it may still take (rate x time on, less what it took)
  };
  struct Checkpoint {
    ParticleState state;
    SpringModel model;
    std::vector<Hold> holds;
    EmbeddedSurface surface;
    std::vector<uint8_t> removed;
    double time = 0;
    int64_t steps = 0, springs_cut = 0, triangles_removed = 0, removed_particles = 0;
    double removed_volume = 0;
  };

  void apply_tools(const std::vector<ToolInput>& tools);
  void release_ended_grabs(const std::vector<ToolInput>& tools);
  void sweep_blade(const ToolInput& blade, const Vec3& from, const Vec3& to);
  void place_stitches(const ToolInput& suture, Hold& hold);
  void remove_tissue(const ToolInput& tool, Hold& hold);
  double spring_sum(int32_t particle) const;  // K_i: the stiffness of the particle's present springs, g/s^2
  void note(const std::string& text) const;
  StabilityGuard make_guard() const;

  SpringModel model_;
  ParticleState state_;
  EmbeddedSurface surface_;
  Vec3 origin_;
  EngineOptions options_;
  std::vector<Real> rest_real_;  // the model's rest positions (#P x 3 mm), as the kernels read them
  std::vector<double> rest_;     // the same in double (exactly)
  CriticalStep critical_;
  double blade_sweep_mm_;        // a quarter of the shortest spring (rest lengths do not change)
  double shortest_spring_mm_;    // mm
  double stitch_unit_stiffness_; // g/s^2
  StepParameters params_;
  StabilityGuard guard_;
  EngineCounts counts_;
  std::unique_ptr<SpringStepper> stepper_;
  std::vector<Hold> holds_;
  std::vector<float> vertices_;  // scratch: the surface for a cut
  std::vector<int32_t> held_components_;  // 3 particle + axis
  double time_ = 0;
  int64_t steps_ = 0, springs_cut_ = 0, triangles_removed_ = 0;
  std::vector<uint8_t> removed_;  // #P, 1 = a remove tool took the particle (empty until one acts)
  int64_t removed_particles_ = 0;
  double removed_volume_ = 0;     // mm^3
  bool tool_work_ = false;       // a tool acted since the last stability check
  std::optional<Checkpoint> checkpoint_;
};

}  // namespace ctsurg::sim
