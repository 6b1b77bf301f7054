// A simulation engine: one model's state and how it moves while tools act on it, whatever the model
// (spring-mass on the voxel grid or on explicit springs: springs/spring_engine.h; tetrahedral FEM,
// dynamic or quasi-static: fem/fem_engine.h) and wherever its state lives (the Backend it was built
// with: the CPU, or a CUDA device). The scenario runner (scenario/scenario_run.h) drives an engine
// along a scenario's tool timeline; anything else that produces tool positions over time (a live
// session driven by a user's input) drives the same engines the same way.
//
// Tools. A time step (step()) or a quasi-static frame (equilibrium()) takes the tools as they are at
// its end, as one ToolInput per tool in a fixed order: the index names the tool to the engine, which
// keeps what the tool holds. An engine never knows which tool it is given (grab, clamp, cautery...: the
// scenario's plug-ins, scenario/tool_type.h); it knows the primitive the tool acts through
// (ToolPrimitive), and a new tool that acts through the existing primitives touches no engine:
//   hold        captures what is inside its sphere when it first becomes active and moves it with its
//               centre until it stops being active (then it lets go, for good): grab, clamp;
//   load        spreads a total force over what is inside its sphere when it starts, until it ends: force;
//   push_sphere pushes the model out of its sphere while active: probe;
//   push_shape  pushes the model out of a rigid closed mesh at a position and an orientation: instrument;
//   separate    cuts what its edge crossed along the straight segments its centre swept since its last
//               sweep (the caller decides when a blade sweeps: blade_sweep_mm()): cut;
//   stitch      joins pairs of points with stitches placed when it starts, tightened over its window and
//               kept after it (springs/suture.h): suture;
//   remove      removes the tissue inside its sphere while active, at most removal_rate_mm3_s of it per
//               second, nearest its centre first; the surface is closed over the crater and the volume
//               removed is counted (EngineMetrics::removed_volume): cautery.
// An engine that cannot act through a primitive says so (InputError naming the tool) when given one.
//
// Frame. Every position an engine takes or gives is in its local frame: LPS minus origin(), in mm (a
// whole-millimetre point near the model, so that float positions keep their resolution far from the
// CT's origin: a heart at z = 650 mm would otherwise move in steps of 6e-5 mm).
//
// Stability. A dynamic engine may find a step unstable (step() says so); check_stability() runs its
// periodic test (the caller decides how often). An engine that can_restart() goes back to its last
// save_checkpoint() with half the step on restart_halved().
//
// Units: mm, s, g (base/particle_state.h): forces uN, energies nJ.
#pragma once

#include "ctsurg/sim/base/instrument.h"
#include "ctsurg/sim/base/real.h"
#include "ctsurg/sim/base/rigid_pose.h"
#include "ctsurg/sim/base/stability_report.h"

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace ctsurg::sim {

using Vec3 = std::array<double, 3>;

// How a tool acts on a model (above). -Werror=switch makes every engine's switch name each one.
enum class ToolPrimitive { hold, load, push_sphere, push_shape, separate, stitch, remove };
const char* to_string(ToolPrimitive primitive);

// What a hold captures: the free nodes inside its sphere, held at prescribed displacements (nodes); or
// the material inside it, pulled to the tool by a penalty integrated over the elements, so that what it
// holds does not depend on where the mesh's nodes happen to lie (volume: FEM static and implicit,
// fem/fem_grip.h).
enum class HoldGrip { nodes, volume };

// One tool at the end of a step (or at a quasi-static frame's time). The fields a primitive does not
// name are unused.
struct ToolInput {
  ToolPrimitive acts = ToolPrimitive::hold;
  std::string name;                    // the tool's kind as the scenario names it ("grab", "cautery"), for messages
  std::string label;                   // names the tool in messages, e.g. "tools[0] (grab)"
  double radius_mm = 0;                // hold, load, push_sphere, remove: the sphere's radius, mm
  Vec3 force_n{0, 0, 0};               // load: the total force, N (LPS)
  Vec3 blade_edge_mm{0, 0, 0};         // separate: the blade's edge, centred on its path, mm
  double removal_rate_mm3_s = 0;       // remove: the most tissue it removes per second, mm^3/s (> 0)
  bool active = false;                 // inside its time window
  Vec3 centre{0, 0, 0};                // mm, local frame
  double start_s = 0;                  // when its window opens, s, and where it is then (mm): a
  Vec3 start_centre{0, 0, 0};          //   quasi-static engine captures there
  std::vector<std::array<Vec3, 2>> sweeps;  // separate: straight segments (from, to) its centre swept
                                            //   since its last sweep, in order; empty: no cut now
  std::shared_ptr<const Instrument> instrument;  // push_shape: its shape (base/instrument.h)
  Quaternion orientation = kIdentityRotation;    // push_shape: its rotation now (its frame -> the run's)
  double end_s = 0;                              // when its window closes, s (+inf: the end of the run)
  // stitch: each stitch's two points (mm, local frame), joined when the window opens; its rest length
  // goes to stitch_target_mm by end_s and stays there. stitch_fields names each stitch in messages.
  std::vector<std::array<Vec3, 2>> stitches;
  std::vector<std::string> stitch_fields;
  double stitch_target_mm = 0;                   // mm, >= 0
  double stitch_stiffness_ratio = 1;             // x the model's stiffest spring (> 0)
  HoldGrip grip = HoldGrip::nodes;      // hold: what it captures (above); load: what shares its force (volume:
                                        //   the material inside by volume, fem/fem_tools.h)
  double grip_stiffness_ratio = 1000;   // hold, volume: the penalty per volume, x E / radius^2 (E: the stiffest
                                        //   material it holds), > 0
  double grip_edge_mm = 0;              // hold, load, volume: the width of the band over which the grip fades at its
                                        //   radius, mm, (0, radius]; 0: radius / 4
  double local_region_mm = 0;  // hold, load on an FEM local region (fem_local_region.h): this tool's region
                               // radius, mm; 0: the engine's
};

// What every engine is built with (an engine adds its own: fem_engine.h's solver).
struct EngineOptions {
  double dt = 0;                           // s, a dynamic engine's step; 0 = safety_factor x the critical step
  double safety_factor = 0.5;              // (0, 1]
  double mass_damping = 0;                 // mass-proportional (Rayleigh) damping rate, 1/s (>= 0)
  double stiffness_damping = 0;            // stiffness-proportional (Rayleigh) damping, s (>= 0; implicit FEM)
  std::array<double, 3> gravity{0, 0, 0};  // mm/s^2, LPS
  int threads = 0;                         // CPU threads, 0 = automatic
  double density = 0;                      // g/mm^3, the tissue's: the remove primitive counts volume as mass / density
  std::string where = "engine";            // names the run in messages (a scenario file)
  std::function<void(const std::string&)> note;  // what the engine decides (captures...), for a log; may be empty
};

// What the model is, for reports.
struct EngineCounts {
  int64_t nodes = 0;          // particles (spring models) or nodes (FEM)
  int64_t fixed = 0;          // of them, held fixed (every axis)
  int64_t partly_fixed = 0;   // of them, held in some axes only (rollers, symmetry planes): tools move their free axes
  int64_t springs = 0;        // spring models: springs present at the start
  int64_t elements = 0;       // FEM: tets
  double critical_dt_s = 0;   // the critical time step (dynamic engines), s
};

// The state's measures at a frame (after sync()).
struct EngineMetrics {
  double kinetic_energy = 0;     // nJ
  double elastic_energy = 0;     // nJ
  double max_displacement = 0;   // mm, over the nodes
  int64_t springs_cut = 0;       // cumulative
  int64_t triangles_removed = 0; // surface triangles the blade removed, cumulative
  double removed_volume = 0;     // mm^3 of tissue the remove primitive took away (cautery), cumulative
  std::vector<double> extra;     // the values of extra_metrics(), in its order
};

class SimulationEngine {
 public:
  virtual ~SimulationEngine() = default;

  // The model.
  virtual EngineCounts counts() const = 0;
  virtual const Vec3& origin() const = 0;                         // LPS mm of the local frame's origin
  virtual const std::vector<double>& rest_positions() const = 0;  // #P x 3 mm, local (the model's own values)
  // The model's elements over rest_positions() (FEM tets: #E x 4, or #E x 10 for quadratic ones in
  // VTK_QUADRATIC_TETRA's node order) into ids; returns the nodes per element, 0 (ids empty) for a model
  // without elements (springs, vessels).
  virtual int32_t elements(std::vector<int32_t>& ids) const {
    ids.clear();
    return 0;
  }
  virtual bool has_surface() const = 0;
  // Metrics beyond EngineMetrics' fixed ones: (name, units), e.g. a static solver's iterations.
  virtual std::vector<std::pair<std::string, std::string>> extra_metrics() const { return {}; }
  // How far a blade's centre moves before it cuts (mm): sweeping shorter than the model's finest spacing
  // costs a pass over the model for nothing. 0 when this engine does not cut.
  virtual double blade_sweep_mm() const = 0;

  // Time.
  virtual bool quasi_static() const = 0;  // each frame an equilibrium (equilibrium()), no time steps
  virtual double dt() const = 0;          // s, the step now (0 when quasi-static)
  virtual double time() const = 0;        // s
  virtual int64_t steps() const = 0;      // steps taken (quasi-static: Newton iterations)
  // Whether step(tools, n) with n > 1 saves work (the caller passes n > 1 only while no tool acts).
  virtual bool batches_steps() const { return false; }
  // Dynamic engines: advances `steps` steps of dt() with the tools as `tools` says (at time() + dt()).
  // Returns unstable (and keeps the state before the failing step) when a per-step guard fired.
  virtual StabilityReport step(const std::vector<ToolInput>& tools, int steps) = 0;
  // Quasi-static engines: the equilibrium at `time` (s) under the tools as `tools` says then.
  virtual void equilibrium(const std::vector<ToolInput>& tools, double time) = 0;

  // Output, from the host's copy of the state: sync() first (a device engine copies it back).
  virtual void sync() = 0;
  virtual void positions(std::vector<double>& xyz) const = 0;   // #P x 3 mm, local
  // The surface's vertices (#V x 3 mm, local), or the nodes' positions when there is no surface.
  virtual void surface_vertices(std::vector<float>& xyz) = 0;
  virtual const std::vector<uint32_t>& triangles() const = 0;  // the surface now (#F x 3); empty: none
  // How many of triangles()' last triangles close the holes a cut left (surface/hole_filling.h).
  virtual int64_t closing_triangles() const { return 0; }
  virtual const std::vector<Real>& surface_rest_vertices() const = 0;  // #V x 3 mm, local; empty: none
  virtual EngineMetrics metrics() const = 0;
  // Whether tool `tool` (an index into the tool list) holds something: a hold its capture, a load
  // the nodes it loads.
  virtual bool engaged(size_t tool) const = 0;
  // The load tool `tool` exerts on the tissue now: the total force (N, LPS axes) and its moment about the
  // tool's centre (N mm); the tissue pulls the tool with the opposite (what a haptic device renders).
  // Returns false (load untouched) when the tool holds nothing or the engine does not measure it.
  virtual bool tool_load([[maybe_unused]] size_t tool, [[maybe_unused]] std::array<double, 6>& load) const { return false; }
  // A stitch tool's stitches now (tool: an index into the tool list): each stitch's two points (mm, local
  // frame; they move with the nodes they joined). Empty before the stitches are placed, and for an
  // engine without sutures.
  virtual std::vector<std::array<Vec3, 2>> stitches([[maybe_unused]] size_t tool) const { return {}; }
  // The region an engine solves with its full model while the rest follows a cheaper one (an FEM local
  // region: fem/fem_local_region.h), per surface vertex (#V as surface_vertices(); the nodes without a
  // surface): 0 outside, 1 in the region, 2 on its interface. Returns false (flags untouched) for an
  // engine or a run without one.
  virtual bool surface_vertex_region([[maybe_unused]] std::vector<uint8_t>& flags) const { return false; }

  // Stability and restarts.
  virtual StabilityReport check_stability() = 0;
  virtual bool can_restart() const = 0;
  virtual void save_checkpoint() = 0;
  virtual void restart_halved() = 0;  // the last checkpoint, with half the step
};

}  // namespace ctsurg::sim
