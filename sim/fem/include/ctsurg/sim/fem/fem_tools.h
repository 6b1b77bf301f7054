// The tools of a tetrahedral FEM model (fem_engine.h), on its nodes:
//
// A node held in some axes only (a roller or symmetry-plane support: FixedRegionSpec::axes) is captured
// too, and the tools act on its free axes: a grab prescribes its held axes at 0 (where the support
// holds them), a force's component along an axis is shared by the captured nodes free in that axis.
//
//   grab   captures the free nodes inside its sphere once, when it first becomes active, with their
//          displacement then; afterwards they are held (prescribed displacements: the static solver's
//          FemBoundaryConditions, the explicit dynamics' set_prescribed) at that displacement plus the
//          tool's travel since the capture, until it stops being active. A node two grabs hold follows
//          the later one in tool order.
//   grab with grip: volume (ToolInput::grip) holds the material inside its sphere instead, by a penalty
//          integrated over the elements (fem_grip.h), captured as a node grab is and moved by the tool's
//          travel since; static and implicit solvers take it as a load (FemLoads::grips).
//   force  a total force (N) shared equally by the free nodes inside its sphere when it starts, as
//          nodal forces (uN) until it ends (the FEM paper's point load, Huang et al. section 5).
//   force with grip: volume spreads it over the material inside its sphere instead, as a body force of
//          uniform density F / V_w: node a carries F m_a / sum m, m_a = integral of w N_a dV over the
//          elements (the volume grip's weight w and quadrature, fem_grip.h: the row sums of its P at
//          k = 1), so the load converges as the mesh is refined where a node count changes with it. A
//          node held in some axis carries its share there too (its support takes it); any solver.
//
// A quasi-static engine captures where the tool was when its window opened (ToolInput::start_centre,
// start_s); a dynamic one where it is at the step it first is active. Both take the displacement the
// caller passes as the nodes' current one.
//
// Units: mm (the model's frame), forces uN (= g mm/s^2), arrays #N x 3 row-major.
#pragma once

#include "ctsurg/sim/base/simulation_engine.h"
#include "ctsurg/sim/fem/fem_grip.h"
#include "ctsurg/sim/fem/fem_model.h"

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace ctsurg::sim {

// Every axis of a node held (held_axes masks: bit a for axis a).
inline constexpr uint8_t kAllAxes = 7;

// The nodes not wholly held (increasing ids) whose current position rest + u lies strictly inside the
// sphere (centre mm, radius mm). held_axes: #N masks (bit a: axis a held; kAllAxes: never selected);
// u: #N x 3 mm.
std::vector<int32_t> free_nodes_in_sphere(const FemModel& model, const std::vector<double>& u,
                                          const std::vector<uint8_t>& held_axes, const Vec3& centre, double radius);

// What the tools hold, by tool index. `where` names the run in messages (InputError(where, tool
// label, ...) when a tool captures nothing); `note` receives what was captured (may be empty).
class FemToolHolds {
 public:
  // held_axes: #N masks, as free_nodes_in_sphere's.
  FemToolHolds(const FemModel& model, std::vector<uint8_t> held_axes, std::string where,
               std::function<void(const std::string&)> note = {});

  // The grabs at time t (s) from the grab entries of `tools`: captures (at `t`, or at each tool's
  // start when capture_at_start) and releases, then writes the held nodes (in tool order, each node
  // once) and their displacements (#G x 3 mm). u: the nodes' displacement now (#N x 3 mm).
  void update_grabs(const std::vector<ToolInput>& tools, double t, const std::vector<double>& u, bool capture_at_start,
                    std::vector<int32_t>& nodes, std::vector<double>& displacements);
  // The volume grips at time t (the grab entries with grip: volume): captures and releases as
  // update_grabs, then writes the engaged grips, their targets moved with their tools, in tool order.
  void update_grips(const std::vector<ToolInput>& tools, double t, const std::vector<double>& u, bool capture_at_start,
                    std::vector<FemGrip>& grips);
  // The load tool `tool` exerts on the tissue (force N, moment about its centre N mm): a volume grip's
  // from its penalty at u (#N x 3 mm); a node grab's the sum of `reactions` (#N x 3 uN, the solver's:
  // what the held components need) over its nodes; a force tool's the force it shares among its nodes.
  // False when it holds nothing, or (a node grab) no reactions are given.
  bool load(size_t tool, const std::vector<double>& u, const std::vector<double>* reactions, std::array<double, 6>& out) const;
  // The forces from the force entries of `tools`: captures and releases as the grabs.
  // Returns whether the nodal forces changed (a force started or ended).
  bool update_forces(const std::vector<ToolInput>& tools, const std::vector<double>& u, bool capture_at_start);
  // The external nodal forces of the active forces (#N x 3 uN), or empty when none acts.
  const std::vector<double>& nodal_forces() const { return nodal_forces_; }
  // Whether tool `tool` holds nodes (a grab its capture, a force the nodes it loads).
  bool engaged(size_t tool) const;
  // The nodes tool `tool` holds (a grab's capture, a force's loaded nodes; increasing), empty when none.
  const std::vector<int32_t>& held_nodes(size_t tool) const;
  // After a cut split nodes (fem_cutting.h): node N + k copies parents[k] (N: the count before); a copy
  // of a node is held in the axes its parent is. What the tools hold stays as it is.
  void nodes_added(const std::vector<int32_t>& parents);
  // Whether an update with `tools` captures (a grab or force active that has not captured yet): the
  // caller passes the nodes' current displacement then.
  bool captures(const std::vector<ToolInput>& tools) const;

 private:
  struct Hold {
    std::vector<int32_t> nodes;     // captured (increasing); empty before the capture and after release
    std::vector<double> captured_u; // #nodes x 3 mm: their displacement at the capture
    Vec3 captured_at{0, 0, 0};      // the tool's centre at the capture
    Vec3 centre{0, 0, 0};           // the tool's centre at the last update
    bool released = false;
    FemGrip grip;                   // a volume grip's (its elements empty before the capture and after release)
    bool force = false;             // a force tool's hold (its nodes are loaded, not held)
    Vec3 force_n{0, 0, 0};          // a force tool's total force, N
    std::vector<double> weights;    // a volume force's share of the force per node of `nodes` (sums to 1);
                                    //   empty: equal shares among the nodes free in each axis
  };
  Hold& hold(size_t tool);
  void spread_over_volume(const FemGrip& region, Hold& hold);
  std::vector<int32_t> capture(const ToolInput& tool, const Vec3& centre, const std::vector<double>& u) const;
  // out (#N x 3 uN) += force_n (N) shared by the hold's nodes: by its weights, or equally, axis by axis,
  // by the nodes free in that axis.
  void add_shared_force(const Hold& hold, const Vec3& force_n, std::vector<double>& out) const;

  const FemModel& model_;
  std::vector<uint8_t> held_axes_;
  std::string where_;
  std::function<void(const std::string&)> note_;
  std::vector<Hold> holds_;
  std::vector<double> nodal_forces_;
  std::vector<int64_t> last_;  // scratch: the last grab entry per node
};

}  // namespace ctsurg::sim
