// FemDeviceDynamics (fem_device_dynamics.h): the CUDA launchers of the explicit FEM step. Each kernel
// is a one-line body around a per-index CTSURG_HD function of the CPU launchers (fem_forces_cpu.cpp):
// fem_element_force_pass (one thread per element), fem_node_update (one thread per node: the CSR
// gather in the CPU's order, then the central-difference update), fem_sphere_contact_node (one thread
// per node). Compiled with -fmad=false, as fem_forces_cpu.cpp is with -ffp-contract=off, so a step
// rounds as the CPU's does (tests/sim/test_fem_device.cpp states the tolerance).
//
// Memory (all on the device for the object's life; nothing comes back unless asked):
//   element data as on the CPU: tets #T x 4 int32, B #T x 9 and V #T as Real (float), corner forces
//     #T x 12 Real (scratch: each element writes its own 12 slots, no atomics);
//   node data: CSR offsets #N + 1 and (element, corner) entries #T x 4, inverse masses #N, masses #N
//     and rest positions #N x 3 (double, for the energy and the sphere), external forces #N x 3 or none;
//   three generations of displacements #N x 3 Real, u(t - dt), u(t), u(t + dt), rotating by index as
//     the CPU swaps vectors (u(t) is generation cur);
//   the guard's Status (below), 64 bytes, read back once per step() call.
//
// One step = element kernel, node kernel, [prescribed nodes], [sphere], finish (1 thread): 3 to 5
// launches. The guard needs no host round trip per step: the element kernel records the lowest
// inverted element (atomicMin), the node kernel the lowest non-finite node; the finish kernel then
// either counts the step as applied or sets `stopped`, after which every kernel of the queued steps
// returns at once. Since the step's results went to the scratch generation, the kept state is exactly
// the one before the failing step (the CPU's rollback, not a per-batch approximation). Every
// energy_check_interval steps two kernels sum the kinetic energy (device_reduction.cuh: deterministic)
// and compare it with the last check's on the device.
//
// Launch overhead: a small model's step is a few microseconds of GPU work, about one launch. Release
// builds record a chunk of energy_check_interval steps plus its check (from step counts that are a
// multiple of the interval) as a CUDA graph, once per starting generation (the rotation makes up to 3
// variants) and per kernel set (prescribed nodes, external forces, sphere on or off), and replay it;
// the sphere and all arrays are read through device pointers, so moving a grab or a probe between calls
// does not recapture. Other steps (a chunk's start or end, intervals above kMaxGraphSteps, debug
// builds) are launched directly; debug builds synchronise after every launch.
#include "fem_device_dynamics.h"
#include "fem_element_view.h"

#include "ctsurg/sim/base/cuda_support.cuh"
#include "ctsurg/sim/base/device_reduction.cuh"
#include "ctsurg/sim/fem/kernels/fem_explicit_step_impl.h"
#include "ctsurg/sim/fem/kernels/fem_forces_impl.h"

#include "ctsurg/sim/base/backend.h"

#include <algorithm>
#include <climits>

namespace ctsurg::sim {
namespace {

constexpr int kBlock = 256;  // threads per block of every kernel
constexpr int32_t kNone = INT32_MAX;
#if defined(NDEBUG)
constexpr int kMaxGraphSteps = 256;  // longest energy_check_interval recorded as one graph
#else
constexpr int kMaxGraphSteps = 0;  // debug: direct launches, each synchronised
#endif

// The guard's state on the device. Written by the kernels as described at the top; the host writes it
// at construction and clears a stop after reading it.
struct Status {
  int32_t stopped;                    // 1: the guard stopped the run; every later kernel returns
  int32_t inverted_element;           // lowest inverted element of the running step, or kNone
  int32_t non_finite_node;            // lowest node whose new displacement is not finite, or kNone
  int32_t energy_grew;                // 1: the last check found growth (energy_before -> energy_after)
  int64_t steps_done;                 // steps applied since construction
  unsigned long long contact_count;   // nodes moved by the sphere in the running step
  unsigned long long contacts;        // ... in the last applied step
  double last_energy;                 // kinetic energy of the last passed check, nJ (-1: none yet)
  double energy_before, energy_after;  // nJ
};

// Whether the running step has been stopped (by an earlier step or by this step's element or node pass).
__device__ inline bool step_stopped(const Status* s) {
  return s->stopped || s->inverted_element != kNone || s->non_finite_node != kNone;
}

// ---- One step: kernels in launch order. ----

// `stopped` is only set by earlier kernels, so every inverted element of this step is recorded.
__global__ void __launch_bounds__(kBlock) element_kernel(FemElementView<Real> el, const Real* u, Real* corner_forces,
                                                         Status* status) {
  const int32_t e = static_cast<int32_t>(blockIdx.x * blockDim.x + threadIdx.x);
  if (e >= el.count || status->stopped) return;
  if (!fem_element_force_pass(el, u, e, corner_forces)) atomicMin(&status->inverted_element, e);
}

__global__ void __launch_bounds__(kBlock) node_kernel(FemNodeView v, FemStepConstants k, const Real* corner_forces,
                                                      Status* status) {
  const int32_t i = static_cast<int32_t>(blockIdx.x * blockDim.x + threadIdx.x);
  if (i >= v.count || status->stopped || status->inverted_element != kNone) return;
  if (!fem_node_update(v, k, corner_forces, i)) atomicMin(&status->non_finite_node, i);
}

// u(t + dt) of prescribed node g set to its value (the CPU's loop in FemExplicitDynamics::step).
__global__ void __launch_bounds__(kBlock) prescribed_kernel(Real* u_next, const int32_t* nodes, const Real* values,
                                                            int32_t count, const Status* status) {
  const int32_t g = static_cast<int32_t>(blockIdx.x * blockDim.x + threadIdx.x);
  if (g >= count || step_stopped(status)) return;
  const int32_t n = nodes[g];
  u_next[3 * n] = values[3 * g];
  u_next[3 * n + 1] = values[3 * g + 1];
  u_next[3 * n + 2] = values[3 * g + 2];
}

// The count is an integer: the atomic sum is exact and order-independent.
__global__ void __launch_bounds__(kBlock) sphere_kernel(Real* u_next, const double* rest, const Real* inv_mass,
                                                        int32_t count, const FemSphereView* sphere, Status* status) {
  const int32_t i = static_cast<int32_t>(blockIdx.x * blockDim.x + threadIdx.x);
  if (i >= count || step_stopped(status)) return;
  if (fem_sphere_contact_node(u_next, rest, inv_mass, *sphere, i)) atomicAdd(&status->contact_count, 1ull);
}

// One thread: the step is applied (counted) or the run stops.
__global__ void finish_step_kernel(Status* s) {
  if (s->stopped) return;
  if (s->inverted_element != kNone || s->non_finite_node != kNone) {
    s->stopped = 1;
    return;
  }
  ++s->steps_done;
  s->contacts = s->contact_count;
  s->contact_count = 0;
}

// ---- Kinetic energy: per-block partial sums, then one block. ----

// partials[b] = sum over block b's nodes of m_i |u_i - u_prev_i|^2 / (2 dt^2), each node's term
// computed as FemExplicitDynamics::kinetic_energy does on the CPU. gate: skip when stopped (null: never).
__global__ void __launch_bounds__(kBlock) kinetic_partial_kernel(const Real* u, const Real* u_prev, const double* mass,
                                                                 double dt, int32_t count, double* partials,
                                                                 const Status* gate) {
  __shared__ double shared[kBlock];
  if (gate != nullptr && gate->stopped) return;  // the same for every thread: no barrier is skipped by some
  const int32_t i = static_cast<int32_t>(blockIdx.x * blockDim.x + threadIdx.x);
  double e = 0;
  if (i < count) {
    double v2 = 0;
    for (int c = 0; c < 3; ++c) {
      const double v = (static_cast<double>(u[3 * i + c]) - u_prev[3 * i + c]) / dt;
      v2 += v * v;
    }
    e = 0.5 * mass[i] * v2;
  }
  e = cuda::block_sum<kBlock>(e, shared);
  if (threadIdx.x == 0) partials[blockIdx.x] = e;
}

// One block: the guard's check (FemExplicitDynamics::step's rule, on the device).
__global__ void __launch_bounds__(kBlock) energy_check_kernel(const double* partials, int64_t count, FemDeviceGuard g,
                                                              Status* s) {
  __shared__ double shared[kBlock];
  if (s->stopped) return;
  const double e = cuda::sum_in_one_block<kBlock>(partials, count, shared);
  if (threadIdx.x != 0) return;
  if (s->last_energy > g.energy_floor && e > g.energy_growth * s->last_energy) {
    s->energy_grew = 1;
    s->energy_before = s->last_energy;
    s->energy_after = e;
    s->stopped = 1;
  } else {
    s->last_energy = e;
  }
}

__global__ void __launch_bounds__(kBlock) sum_kernel(const double* partials, int64_t count, double* sum) {
  __shared__ double shared[kBlock];
  const double e = cuda::sum_in_one_block<kBlock>(partials, count, shared);
  if (threadIdx.x == 0) *sum = e;
}

// ---- On request. ----

__global__ void __launch_bounds__(kBlock) zero_nodes_kernel(Real* u, Real* u_prev, const int32_t* nodes, int32_t count) {
  const int32_t g = static_cast<int32_t>(blockIdx.x * blockDim.x + threadIdx.x);
  if (g >= count) return;
  for (int c = 0; c < 3; ++c) u[3 * nodes[g] + c] = u_prev[3 * nodes[g] + c] = 0;
}

// The element pass without the guard (internal_forces reports forces, not inversions, as on the CPU).
__global__ void __launch_bounds__(kBlock) element_forces_kernel(FemElementView<Real> el, const Real* u, Real* corner_forces) {
  const int32_t e = static_cast<int32_t>(blockIdx.x * blockDim.x + threadIdx.x);
  if (e >= el.count) return;
  fem_element_force_pass(el, u, e, corner_forces);
}

__global__ void __launch_bounds__(kBlock) gather_kernel(const int32_t* offsets, const int32_t* corners,
                                                        const Real* corner_forces, int32_t count, Real* forces) {
  const int32_t i = static_cast<int32_t>(blockIdx.x * blockDim.x + threadIdx.x);
  if (i >= count) return;
  fem_gather_node_force(offsets, corners, corner_forces, i, forces + 3 * i);
}

// What a recorded chunk depends on besides generation and constants: the kernels launched and the
// buffers they read whose address can change.
struct ChunkKey {
  const int32_t* prescribed_nodes = nullptr;
  const Real* prescribed_values = nullptr;
  std::size_t prescribed = 0;
  const Real* external = nullptr;
  bool sphere = false;
  bool operator==(const ChunkKey&) const = default;
};

}  // namespace

struct FemDeviceDynamics::Device {
  int ordinal = 0;
  cuda::Stream stream;
  FemStepConstants constants{};
  double dt = 0;
  FemDeviceGuard guard;
  int32_t nodes = 0;
  FemElementView<Real> elements{};  // device pointers

  cuda::DeviceBuffer<int32_t> tets, offsets, corners, element_material;
  cuda::DeviceBuffer<Real> dm_inverse, volume, corner_forces, forces, inv_mass, external;
  cuda::DeviceBuffer<double> rest, mass, partials, energy;
  cuda::DeviceBuffer<Real> u[3];  // displacement generations; u(t) = u[cur]
  int cur = 0;
  cuda::DeviceBuffer<int32_t> prescribed_nodes, zero_ids;
  cuda::DeviceBuffer<Real> prescribed_values;
  cuda::DeviceBuffer<FemSphereView> sphere;  // one element
  bool sphere_on = false;
  cuda::DeviceBuffer<Status> status;         // one element
  cuda::PinnedValue<Status> status_host;
  cuda::PinnedValue<double> energy_host;
  FemSphereView sphere_host{};               // staging for the sphere's upload

  cuda::Graph chunk[3];  // a chunk of guard.energy_check_interval steps and its check, from generation 0, 1, 2
  ChunkKey chunk_key;

  ~Device() { cuda::release_check(cudaStreamSynchronize(stream), "cudaStreamSynchronize"); }

  unsigned node_blocks() const { return cuda::blocks_for(nodes, kBlock); }

  FemNodeView node_view() const {
    const int prev = (cur + 2) % 3, next = (cur + 1) % 3;
    return {offsets.data(), corners.data(), u[cur].data(), u[prev].data(), u[next].data(), inv_mass.data(),
            external.size() > 0 ? external.data() : nullptr, nodes};
  }

  ChunkKey key() const {
    return {prescribed_nodes.data(), prescribed_values.data(), prescribed_nodes.size(),
            external.size() > 0 ? external.data() : nullptr, sphere_on};
  }

  // Queues one step from generation cur, then rotates.
  void launch_step() {
    const FemNodeView v = node_view();
    element_kernel<<<cuda::blocks_for(elements.count, kBlock), kBlock, 0, stream>>>(elements, v.u, corner_forces.data(),
                                                                                   status.data());
    CTSURG_CUDA_LAUNCHED(stream);
    node_kernel<<<node_blocks(), kBlock, 0, stream>>>(v, constants, corner_forces.data(), status.data());
    CTSURG_CUDA_LAUNCHED(stream);
    const auto prescribed = static_cast<int32_t>(prescribed_nodes.size());
    if (prescribed > 0) {
      prescribed_kernel<<<cuda::blocks_for(prescribed, kBlock), kBlock, 0, stream>>>(
          v.u_next, prescribed_nodes.data(), prescribed_values.data(), prescribed, status.data());
      CTSURG_CUDA_LAUNCHED(stream);
    }
    if (sphere_on) {
      sphere_kernel<<<node_blocks(), kBlock, 0, stream>>>(v.u_next, rest.data(), inv_mass.data(), nodes, sphere.data(),
                                                          status.data());
      CTSURG_CUDA_LAUNCHED(stream);
    }
    finish_step_kernel<<<1, 1, 0, stream>>>(status.data());
    CTSURG_CUDA_LAUNCHED(stream);
    cur = (cur + 1) % 3;
  }

  // Kinetic energy of generation cur into partials (gate: the guard's status, or null).
  void launch_kinetic_partials(const Status* gate) {
    kinetic_partial_kernel<<<node_blocks(), kBlock, 0, stream>>>(u[cur].data(), u[(cur + 2) % 3].data(), mass.data(), dt,
                                                                 nodes, partials.data(), gate);
    CTSURG_CUDA_LAUNCHED(stream);
  }

  void launch_energy_check() {
    launch_kinetic_partials(status.data());
    energy_check_kernel<<<1, kBlock, 0, stream>>>(partials.data(), node_blocks(), guard, status.data());
    CTSURG_CUDA_LAUNCHED(stream);
  }

  // A whole chunk from generation cur: replays (recording first if needed) its graph.
  void launch_chunk() {
    const int interval = guard.energy_check_interval;
    cuda::Graph& graph = chunk[cur];
    if (!graph) {
      const int start = cur;
      graph.capture(stream, [&] {
        for (int k = 0; k < interval; ++k) launch_step();
        launch_energy_check();
      });
      cur = start;  // recording ran nothing
    }
    graph.launch(stream);
    cur = (cur + interval) % 3;
  }
};

FemDeviceDynamics::FemDeviceDynamics(const FemModel& model, const std::vector<Real>& dm_inverse,
                                     const std::vector<Real>& volume, const FemStepConstants& constants, double dt,
                                     const FemDeviceGuard& guard, const char* where) {
  if (!backend_available(Backend::cuda)) require_backend(Backend::cuda, where);  // throws why
  cuda::use_device(0);
  device_ = std::make_unique<Device>();
  Device& d = *device_;
  d.constants = constants, d.dt = dt, d.guard = guard;
  d.nodes = model.node_count();
  const auto n3 = 3 * static_cast<std::size_t>(d.nodes);
  d.tets.upload(model.tets, d.stream);
  d.dm_inverse.upload(dm_inverse, d.stream);
  d.volume.upload(volume, d.stream);
  d.offsets.upload(model.node_offsets, d.stream);
  d.corners.upload(model.node_corners, d.stream);
  d.rest.upload(model.nodes, d.stream);
  d.mass.upload(model.node_mass, d.stream);
  d.corner_forces.resize(12 * static_cast<std::size_t>(model.tet_count()));
  d.partials.resize(d.node_blocks());
  d.energy.resize(1);
  for (auto& g : d.u) {
    g.resize(n3);
    g.zero(d.stream);
  }
  d.inv_mass.resize(static_cast<std::size_t>(d.nodes));
  d.inv_mass.zero(d.stream);
  d.sphere.resize(1);
  d.sphere.zero(d.stream);
  *d.status_host = Status{0, kNone, kNone, 0, 0, 0, 0, -1.0, 0, 0};
  d.status.upload(d.status_host.get(), 1, d.stream);
  if (!model.element_material.empty()) d.element_material.upload(model.element_material, d.stream);
  d.elements = fem_element_view<Real>(model, d.dm_inverse.data(), d.volume.data(),
                                      model.element_material.empty() ? nullptr : d.element_material.data());
  d.elements.tets = d.tets.data();
  d.chunk_key = d.key();
  d.stream.synchronize();  // the host arrays may go away after return
}

FemDeviceDynamics::~FemDeviceDynamics() = default;

void FemDeviceDynamics::set_inverse_mass(const std::vector<Real>& inv_mass) {
  Device& d = *device_;
  cuda::use_device(d.ordinal);
  d.inv_mass.upload(inv_mass, d.stream);  // same size: in place, recorded graphs stay valid
  d.stream.synchronize();
}

void FemDeviceDynamics::zero_nodes(const std::vector<int32_t>& nodes) {
  Device& d = *device_;
  cuda::use_device(d.ordinal);
  if (nodes.empty()) return;
  d.zero_ids.upload(nodes, d.stream);
  const auto count = static_cast<int32_t>(nodes.size());
  zero_nodes_kernel<<<cuda::blocks_for(count, kBlock), kBlock, 0, d.stream>>>(d.u[d.cur].data(), d.u[(d.cur + 2) % 3].data(),
                                                                             d.zero_ids.data(), count);
  CTSURG_CUDA_LAUNCHED(d.stream);
  d.stream.synchronize();
}

void FemDeviceDynamics::set_prescribed(const std::vector<int32_t>& nodes, const std::vector<Real>& values) {
  Device& d = *device_;
  cuda::use_device(d.ordinal);
  d.prescribed_nodes.upload(nodes, d.stream);
  d.prescribed_values.upload(values, d.stream);
  d.stream.synchronize();
}

void FemDeviceDynamics::set_external_forces(const std::vector<Real>& forces) {
  Device& d = *device_;
  cuda::use_device(d.ordinal);
  d.external.upload(forces, d.stream);
  d.stream.synchronize();
}

void FemDeviceDynamics::set_contact_sphere(const FemSphereView& sphere) {
  Device& d = *device_;
  cuda::use_device(d.ordinal);
  d.sphere_on = sphere.radius > 0;
  d.sphere_host = sphere;
  d.sphere.upload(&d.sphere_host, 1, d.stream);
  d.stream.synchronize();
}

FemDeviceStepOutcome FemDeviceDynamics::step(int64_t steps, int64_t steps_taken) {
  Device& d = *device_;
  cuda::use_device(d.ordinal);
  const int interval = d.guard.energy_check_interval;
  const bool graphs = interval <= kMaxGraphSteps;
  if (!(d.key() == d.chunk_key)) {
    for (auto& g : d.chunk) g.release();
    d.chunk_key = d.key();
  }
  const int start = d.cur;
  for (int64_t done = 0; done < steps;) {
    const int64_t to_check = interval - (steps_taken + done) % interval;  // steps until the next check
    if (graphs && to_check == interval && steps - done >= interval) {
      d.launch_chunk();
      done += interval;
      continue;
    }
    const int64_t k = std::min(to_check, steps - done);
    for (int64_t j = 0; j < k; ++j) d.launch_step();
    if (k == to_check) d.launch_energy_check();
    done += k;
  }
  d.status.download(d.status_host.get(), 1, d.stream);
  d.stream.synchronize();
  const Status s = *d.status_host;
  FemDeviceStepOutcome out;
  out.completed = s.steps_done - steps_taken;
  out.contacts = static_cast<int64_t>(s.contacts);
  d.cur = static_cast<int>((start + out.completed) % 3);
  if (s.stopped) {
    out.inverted_element = s.inverted_element != kNone ? s.inverted_element : -1;
    out.non_finite_node = s.non_finite_node != kNone ? s.non_finite_node : -1;
    out.energy_grew = s.energy_grew != 0;
    out.energy_before = s.energy_before, out.energy_after = s.energy_after;
    // Ready to step again from the kept state (as the CPU object after its RuntimeError).
    Status cleared = s;
    cleared.stopped = 0, cleared.inverted_element = kNone, cleared.non_finite_node = kNone, cleared.energy_grew = 0;
    cleared.contact_count = 0;
    *d.status_host = cleared;
    d.status.upload(d.status_host.get(), 1, d.stream);
    d.stream.synchronize();
  }
  return out;
}

std::vector<Real> FemDeviceDynamics::displacements() const {
  const Device& d = *device_;
  cuda::use_device(d.ordinal);
  std::vector<Real> u(d.u[d.cur].size());
  d.u[d.cur].download(u.data(), u.size(), d.stream);
  d.stream.synchronize();
  return u;
}

double FemDeviceDynamics::kinetic_energy() const {
  Device& d = *device_;
  cuda::use_device(d.ordinal);
  d.launch_kinetic_partials(nullptr);
  sum_kernel<<<1, kBlock, 0, d.stream>>>(d.partials.data(), d.node_blocks(), d.energy.data());
  CTSURG_CUDA_LAUNCHED(d.stream);
  d.energy.download(d.energy_host.get(), 1, d.stream);
  d.stream.synchronize();
  return *d.energy_host;
}

std::vector<Real> FemDeviceDynamics::internal_forces() {
  Device& d = *device_;
  cuda::use_device(d.ordinal);
  d.forces.resize(3 * static_cast<std::size_t>(d.nodes));
  element_forces_kernel<<<cuda::blocks_for(d.elements.count, kBlock), kBlock, 0, d.stream>>>(d.elements, d.u[d.cur].data(),
                                                                                            d.corner_forces.data());
  CTSURG_CUDA_LAUNCHED(d.stream);
  gather_kernel<<<d.node_blocks(), kBlock, 0, d.stream>>>(d.offsets.data(), d.corners.data(), d.corner_forces.data(),
                                                          d.nodes, d.forces.data());
  CTSURG_CUDA_LAUNCHED(d.stream);
  std::vector<Real> f(d.forces.size());
  d.forces.download(f.data(), f.size(), d.stream);
  d.stream.synchronize();
  return f;
}

}  // namespace ctsurg::sim
