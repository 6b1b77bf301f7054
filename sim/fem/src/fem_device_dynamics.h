// The device side of FemExplicitDynamics with Backend::cuda (fem_explicit_dynamics.h): the explicit
// total-Lagrangian FEM state on a CUDA device for the whole run, stepped there many steps per call.
// Plain C++ (no CUDA types or syntax): fem_explicit_dynamics.cpp (g++) calls it after checking every
// argument (STYLE.md rule 7); fem_device_dynamics_cuda.cu implements it with nvcc, and
// fem_device_stubs.cpp replaces it in a build without CUDA (the constructor refuses).
//
// Kernels: the CPU's per-index functions (fem_forces_impl.h's fem_element_force_pass, one thread per
// element; fem_explicit_step_impl.h's fem_node_update, one thread per node, gathering the corner forces
// through the node -> (element, corner) CSR in the CPU's order; fem_sphere_contact_node), so a step
// computes what cpu::fem_explicit_step does, in the same order of operations.
//
// Stability guard, as the CPU's: an inverted element or a non-finite new displacement stops the run
// before that step is applied (the device keeps the state before it: exact per-step rollback, see
// FemDeviceStepOutcome), and every energy_check_interval steps the kinetic energy (a deterministic
// device sum in double) may not grow by more than energy_growth from above energy_floor.
//
// Units: mm, g, s; forces uN, energies nJ. Arrays #N x 3 row-major as in FemModel.
#pragma once

#include "ctsurg/sim/fem/kernels/fem_explicit_step_impl.h"

#include "ctsurg/sim/fem/fem_model.h"

#include <cstdint>
#include <memory>
#include <vector>

namespace ctsurg::sim {

// FemDynamicsOptions' guard settings (checked by FemExplicitDynamics).
struct FemDeviceGuard {
  int energy_check_interval = 16;  // steps between kinetic-energy checks (>= 1)
  double energy_growth = 100;      // largest ratio of kinetic energies between checks
  double energy_floor = 1e-6;      // nJ; growth from below this is not counted
};

// What step() did. The steps run in order; the first one that the guard stops ends the call:
//   inverted_element >= 0 or non_finite_node >= 0: step `completed` (0-based in this call) would
//     have inverted that element (the lowest id) or made that node's displacement non-finite (the
//     lowest id); it was not applied: the state is the one after `completed` steps;
//   energy_grew: the check after step completed - 1 (which was applied) found the kinetic energy grown
//     from energy_before to energy_after (nJ).
struct FemDeviceStepOutcome {
  int64_t completed = 0;          // steps applied
  int32_t inverted_element = -1;
  int32_t non_finite_node = -1;
  bool energy_grew = false;
  double energy_before = 0, energy_after = 0;
  int64_t contacts = 0;           // nodes the sphere moved in the last applied step (when completed > 0)
};

class FemDeviceDynamics {
 public:
  // Selects CUDA device 0, uploads the model (tets, B = Dm^-1 and V as Real: dm_inverse #T x 9 and
  // volume #T, the node CSR, masses, rest nodes) and a state at rest (u = 0), with every inverse mass 0
  // until set_inverse_mass. `constants` and dt (s) are the step's (fixed for the object's life). Throws
  // InputError(where, "backend", ...) where cuda cannot run (no CUDA build or no device). The model
  // must outlive this object.
  FemDeviceDynamics(const FemModel& model, const std::vector<Real>& dm_inverse, const std::vector<Real>& volume,
                    const FemStepConstants& constants, double dt, const FemDeviceGuard& guard, const char* where);
  ~FemDeviceDynamics();
  FemDeviceDynamics(const FemDeviceDynamics&) = delete;
  FemDeviceDynamics& operator=(const FemDeviceDynamics&) = delete;

  // #N inverse masses (1/g, 0 = held), as FemExplicitDynamics computes them.
  void set_inverse_mass(const std::vector<Real>& inv_mass);
  // Sets u(t) and u(t - dt) of `nodes` to zero (nodes becoming fixed).
  void zero_nodes(const std::vector<int32_t>& nodes);
  // After every step, u(t + dt) of nodes[g] is set to values[3 g .. 3 g + 2] (mm); empty = none.
  void set_prescribed(const std::vector<int32_t>& nodes, const std::vector<Real>& values);
  // #N x 3 external nodal forces (uN), or empty for none.
  void set_external_forces(const std::vector<Real>& forces);
  // The contact sphere (LPS mm); radius 0 = none.
  void set_contact_sphere(const FemSphereView& sphere);

  // Queues `steps` steps (the device places the energy checks after every step whose count, from
  // steps_taken on, is a multiple of energy_check_interval), waits once at the end and reports. After
  // a stop the device is ready to step again from the kept state.
  FemDeviceStepOutcome step(int64_t steps, int64_t steps_taken);

  std::vector<Real> displacements() const;  // u(t), #N x 3 mm (a download)
  // sum_i m_i |u_i(t) - u_i(t - dt)|^2 / (2 dt^2), nJ: the guard's deterministic device sum.
  double kinetic_energy() const;
  // The nodal internal forces of u(t) as the step computes them (element pass + gather), #N x 3 uN.
  std::vector<Real> internal_forces();

  struct Device;  // CUDA handles and buffers (fem_device_dynamics_cuda.cu)

 private:
  std::unique_ptr<Device> device_;
};

}  // namespace ctsurg::sim
