// DeviceSimulation, device side: the CUDA launchers of the sim kernels, device buffers, streams and
// graphs. Each kernel is a one-line loop body around a per-index CTSURG_HD function from the same
// *_impl.h headers the OpenMP launchers include (STYLE.md rule 5; Open3D's *CUDA.cu files): one thread
// per particle, spring, grabbed particle or surface vertex. Views (structs of raw device pointers and
// sizes) are passed to kernels by value; every CUDA call is checked with its file and line, and debug
// builds (NDEBUG undefined) synchronise after each launch (NVIDIA Warp's native code does the same).
//
// State: three generations of positions (x(t - dt), x(t), x(t + dt)) rotate by index on the host, as
// ParticleState::advance() swaps vectors: a step reads generations cur and cur - 1 and writes cur + 1.
// Release builds replay a CUDA graph of kGraphSteps steps (a multiple of 3, so the rotation ends where
// it started), which turns 2 x kGraphSteps kernel launches into one graph launch: at 10^5 particles a
// step is a few microseconds of GPU work, the same as a launch. The graph is captured again only when
// the step constants, the kernel variant or the buffers change; the grab centre lives in device memory
// so that moving a grab does not.
//
// Surface frames: the vertex kernel runs on the compute stream after the queued steps, then a second
// stream copies the frame into pinned host memory while the compute stream goes on stepping. Two
// frame slots (device and pinned) alternate; an event per slot orders reuse.
#include "device_simulation_cuda.cuh"

#include "ctsurg/sim/base/cuda_support.cuh"

#include "ctsurg/sim/springs/kernels/particle_normals_impl.h"
#include "ctsurg/sim/springs/kernels/sphere_tools_impl.h"
#include "ctsurg/sim/springs/kernels/spring_cutting_impl.h"
#include "ctsurg/sim/springs/kernels/spring_forces_impl.h"
#include "ctsurg/sim/springs/kernels/verlet_step_impl.h"
#include "ctsurg/sim/surface/kernels/surface_coupling_impl.h"

#include "ctsurg/core/error.h"

#include <cuda_runtime.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <utility>

namespace ctsurg::sim {

namespace {

constexpr int kBlock = 256;  // threads per block of every kernel
// Steps per graph replay: a multiple of 3 (the position generations' cycle). 48 steps are 48 or 96
// kernel nodes, captured once per step constants.
#if defined(NDEBUG)
constexpr int64_t kGraphSteps = 48;
#else
constexpr int64_t kGraphSteps = 0;  // debug: direct launches, so that each can be synchronised
#endif

int blocks_for(int64_t n) { return static_cast<int>(cuda::blocks_for(n, kBlock)); }

using cuda::DeviceBuffer;
using cuda::release_check;

// ---- Kernels: one thread per index, each calling the per-index function of the CPU launchers. ----

template <bool kDamping, bool kNormals>
__global__ void __launch_bounds__(kBlock) grid_step_kernel(SpringGridView g, ParticleStateView s, VerletConstants c,
                                                           Real* nx, Real* ny, Real* nz) {
  const int32_t i = static_cast<int32_t>(blockIdx.x * blockDim.x + threadIdx.x);
  if (i >= s.count) return;
  const SpringForceSum f = grid_spring_forces<kDamping, kNormals>(g, s, c.inv_dt, i);
  verlet_update(s, c, i, f.fx, f.fy, f.fz);
  if constexpr (kNormals) write_normal(f.ux, f.uy, f.uz, nx, ny, nz, i);
}

template <bool kDamping, bool kNormals>
__global__ void __launch_bounds__(kBlock) explicit_step_kernel(ExplicitSpringView m, ParticleStateView s,
                                                               VerletConstants c, Real* nx, Real* ny, Real* nz) {
  const int32_t i = static_cast<int32_t>(blockIdx.x * blockDim.x + threadIdx.x);
  if (i >= s.count) return;
  const SpringForceSum f = explicit_spring_forces<kDamping, kNormals>(m, s, c.inv_dt, i);
  verlet_update(s, c, i, f.fx, f.fy, f.fz);
  if constexpr (kNormals) write_normal(f.ux, f.uy, f.uz, nx, ny, nz, i);
}

// Grabbed particles to centre + offset; the centre is read from device memory (see the file comment).
__global__ void __launch_bounds__(kBlock) place_grabbed_kernel(Real* x, Real* y, Real* z, const int32_t* ids,
                                                               const Real* offsets, int64_t count,
                                                               const SphereView* centre) {
  const int64_t g = static_cast<int64_t>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (g >= count) return;
  place_grabbed(x, y, z, ids, offsets, *centre, g);
}

// Writes the grab centre from a kernel parameter: ordered on the stream like the launches around it,
// with no host staging buffer that a later call could overwrite before the copy ran.
__global__ void set_centre_kernel(SphereView* centre, SphereView value) { *centre = value; }

__global__ void __launch_bounds__(kBlock) grabbable_kernel(const Real* x, const Real* y, const Real* z,
                                                           const Real* inv_mass, int32_t count, SphereView tool,
                                                           uint8_t* inside) {
  const int32_t i = static_cast<int32_t>(blockIdx.x * blockDim.x + threadIdx.x);
  if (i >= count) return;
  inside[i] = grabbable(x, y, z, inv_mass, tool, i) ? 1 : 0;
}

// Offsets of the grabbed particles from the centre, as grab_particles_in_sphere computes them.
__global__ void __launch_bounds__(kBlock) grab_offsets_kernel(const Real* x, const Real* y, const Real* z,
                                                              const int32_t* ids, int64_t count, SphereView tool,
                                                              Real* offsets) {
  const int64_t g = static_cast<int64_t>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (g >= count) return;
  const int32_t p = ids[g];
  offsets[3 * g] = x[p] - tool.cx, offsets[3 * g + 1] = y[p] - tool.cy, offsets[3 * g + 2] = z[p] - tool.cz;
}

// Counts are integers, so the atomic sums are exact and order-independent.
__global__ void __launch_bounds__(kBlock) probe_kernel(Real* x, Real* y, Real* z, const Real* inv_mass, int32_t count,
                                                       SphereView tool, unsigned long long* moved) {
  const int32_t i = static_cast<int32_t>(blockIdx.x * blockDim.x + threadIdx.x);
  if (i >= count) return;
  if (probe_particle(x, y, z, inv_mass, tool, i)) atomicAdd(moved, 1ull);
}

// The mask is read and written by particle i's own thread only (grid_mask_after_cut reads i's mask).
__global__ void __launch_bounds__(kBlock) cut_grid_kernel(SpringGridView g, uint32_t* spring_mask, const Real* x,
                                                          const Real* y, const Real* z, TriangleView blade,
                                                          unsigned long long* cleared) {
  const int32_t i = static_cast<int32_t>(blockIdx.x * blockDim.x + threadIdx.x);
  if (i >= g.count) return;
  const uint32_t before = spring_mask[i];
  const uint32_t after = grid_mask_after_cut(g, x, y, z, blade, i);
  spring_mask[i] = after;
  const int n = __popc(before & ~after);
  if (n > 0) atomicAdd(cleared, static_cast<unsigned long long>(n));
}

__global__ void __launch_bounds__(kBlock) cut_explicit_kernel(const int32_t* ends, uint8_t* alive, int32_t springs,
                                                              const Real* x, const Real* y, const Real* z,
                                                              TriangleView blade, unsigned long long* cut) {
  const int32_t s = static_cast<int32_t>(blockIdx.x * blockDim.x + threadIdx.x);
  if (s >= springs) return;
  const uint8_t after = explicit_alive_after_cut(ends, alive, x, y, z, blade, s);
  if (alive[s] != after) {
    alive[s] = after;
    atomicAdd(cut, 1ull);
  }
}

__global__ void __launch_bounds__(kBlock) move_surface_kernel(SurfaceCouplingView v) {
  const int64_t i = static_cast<int64_t>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (i >= v.count) return;
  move_vertex(v, i);
}

}  // namespace

struct DeviceSimulation::Impl::Device {
  int ordinal = 0;
  cudaStream_t compute = nullptr, copy = nullptr;

  // Positions: generation g, axis a in pos[g][a]; x(t) is generation cur.
  DeviceBuffer<Real> pos[3][3];
  int cur = 0;
  DeviceBuffer<Real> inv_mass;
  std::vector<Real> mass_host, inv_mass_host;  // as uploaded, for download_state

  // Grid model (chunk_offsets stays null: the CPU's index).
  DeviceBuffer<int32_t> neighbours;
  DeviceBuffer<uint32_t> spring_mask;
  SpringGridView grid{};
  // Explicit model (CSR rows; the CPU's sliced layout stays on the host).
  DeviceBuffer<int32_t> row_offsets, row_neighbour, row_spring, spring_ends;
  DeviceBuffer<Real> stiffness, rest_length, damping;
  DeviceBuffer<uint8_t> alive;
  ExplicitSpringView springs{};

  // Grabs: one slot per held grab (a handle is a slot index; released slots are reused, lowest first).
  struct GrabSlot {
    DeviceBuffer<int32_t> ids;
    DeviceBuffer<Real> offsets;
    DeviceBuffer<SphereView> centre;  // one element
    int64_t count = 0;
    bool held = false;
  };
  std::vector<std::unique_ptr<GrabSlot>> grabs;
  DeviceBuffer<uint8_t> flags;

  // Counters of the tool kernels.
  DeviceBuffer<unsigned long long> counter;
  unsigned long long* counter_host = nullptr;  // pinned

  // Normals output.
  DeviceBuffer<Real> normal[3];

  // Surface.
  DeviceBuffer<int32_t> surface_particles;
  DeviceBuffer<Real> surface_weights, surface_rest, rest_positions;
  DeviceBuffer<float> vertices[2];
  float* frame[2] = {nullptr, nullptr};  // pinned
  cudaEvent_t kernel_done[2] = {nullptr, nullptr}, copy_done[2] = {nullptr, nullptr};

  // The step graph and what it was captured for.
  cudaGraphExec_t graph = nullptr;
  VerletConstants graph_constants{};
  bool graph_grab = false;

  ~Device() {
    if (graph != nullptr) release_check(cudaGraphExecDestroy(graph), "cudaGraphExecDestroy");
    for (int k = 0; k < 2; ++k) {
      if (frame[k] != nullptr) release_check(cudaFreeHost(frame[k]), "cudaFreeHost");
      if (kernel_done[k] != nullptr) release_check(cudaEventDestroy(kernel_done[k]), "cudaEventDestroy");
      if (copy_done[k] != nullptr) release_check(cudaEventDestroy(copy_done[k]), "cudaEventDestroy");
    }
    if (counter_host != nullptr) release_check(cudaFreeHost(counter_host), "cudaFreeHost");
    if (compute != nullptr) release_check(cudaStreamDestroy(compute), "cudaStreamDestroy");
    if (copy != nullptr) release_check(cudaStreamDestroy(copy), "cudaStreamDestroy");
  }

  void drop_graph() {
    if (graph != nullptr) CTSURG_CUDA_CHECK(cudaGraphExecDestroy(graph));
    graph = nullptr;
  }

  ParticleStateView state_view() const {
    const int prev = (cur + 2) % 3, next = (cur + 1) % 3;
    return {pos[cur][0].data(),  pos[cur][1].data(),  pos[cur][2].data(),  pos[prev][0].data(),
            pos[prev][1].data(), pos[prev][2].data(), pos[next][0].data(), pos[next][1].data(),
            pos[next][2].data(), inv_mass.data(),     static_cast<int32_t>(inv_mass.size())};
  }
  Real* x(int a) const { return pos[cur][a].data(); }

  bool any_grab() const {
    return std::any_of(grabs.begin(), grabs.end(), [](const auto& g) { return g->held && g->count > 0; });
  }

  // One step's kernels on `stream` (the grabs after the spring step, in handle order), then the
  // rotation.
  void launch_step(UploadedModel kind, bool damped, const VerletConstants& c, cudaStream_t stream) {
    const ParticleStateView s = state_view();
    const int blocks = blocks_for(s.count);
    if (blocks > 0) {
      if (kind == UploadedModel::grid) {
        if (damped)
          grid_step_kernel<true, false><<<blocks, kBlock, 0, stream>>>(grid, s, c, nullptr, nullptr, nullptr);
        else
          grid_step_kernel<false, false><<<blocks, kBlock, 0, stream>>>(grid, s, c, nullptr, nullptr, nullptr);
      } else {
        if (damped)
          explicit_step_kernel<true, false><<<blocks, kBlock, 0, stream>>>(springs, s, c, nullptr, nullptr, nullptr);
        else
          explicit_step_kernel<false, false><<<blocks, kBlock, 0, stream>>>(springs, s, c, nullptr, nullptr, nullptr);
      }
      CTSURG_CUDA_LAUNCHED(stream);
    }
    cur = (cur + 1) % 3;
    for (const auto& g : grabs) {
      if (!g->held || g->count == 0) continue;
      place_grabbed_kernel<<<blocks_for(g->count), kBlock, 0, stream>>>(x(0), x(1), x(2), g->ids.data(), g->offsets.data(),
                                                                         g->count, g->centre.data());
      CTSURG_CUDA_LAUNCHED(stream);
    }
  }

  unsigned long long read_counter() {
    CTSURG_CUDA_CHECK(cudaMemcpyAsync(counter_host, counter.data(), sizeof(unsigned long long), cudaMemcpyDeviceToHost,
                                      compute));
    CTSURG_CUDA_CHECK(cudaStreamSynchronize(compute));
    return *counter_host;
  }
  void zero_counter() { CTSURG_CUDA_CHECK(cudaMemsetAsync(counter.data(), 0, sizeof(unsigned long long), compute)); }
};

DeviceSimulation::Impl::Impl(int ordinal) {
  if (cuda_device_count() == 0) require_backend(Backend::cuda, "device simulation");  // no device: refuse
  if (ordinal < 0 || ordinal >= cuda_device_count())
    throw InputError("device simulation", "device",
                     "ordinal " + std::to_string(ordinal) + " out of range: " + std::to_string(cuda_device_count()) +
                         " CUDA device(s)");
  device = std::make_unique<Device>();
  Device& d = *device;
  d.ordinal = ordinal;
  CTSURG_CUDA_CHECK(cudaSetDevice(ordinal));
  CTSURG_CUDA_CHECK(cudaStreamCreateWithFlags(&d.compute, cudaStreamNonBlocking));
  CTSURG_CUDA_CHECK(cudaStreamCreateWithFlags(&d.copy, cudaStreamNonBlocking));
  CTSURG_CUDA_CHECK(cudaMallocHost(reinterpret_cast<void**>(&d.counter_host), sizeof(unsigned long long)));
  for (int k = 0; k < 2; ++k) {
    CTSURG_CUDA_CHECK(cudaEventCreateWithFlags(&d.kernel_done[k], cudaEventDisableTiming));
    CTSURG_CUDA_CHECK(cudaEventCreateWithFlags(&d.copy_done[k], cudaEventDisableTiming));
  }
  d.counter.resize(1);
}

DeviceSimulation::Impl::~Impl() {
  if (device != nullptr) release_check(cudaDeviceSynchronize(), "cudaDeviceSynchronize");
}

DeviceInfo DeviceSimulation::Impl::info() const { return cuda_device_info(device->ordinal); }

void DeviceSimulation::Impl::upload_state(const ParticleState& state) {
  Device& d = *device;
  CTSURG_CUDA_CHECK(cudaSetDevice(d.ordinal));
  CTSURG_CUDA_CHECK(cudaStreamSynchronize(d.compute));  // nothing queued reads the old buffers any more
  const std::vector<Real>* current[3] = {&state.x, &state.y, &state.z};
  const std::vector<Real>* previous[3] = {&state.px, &state.py, &state.pz};
  d.cur = 0;
  for (int a = 0; a < 3; ++a) {
    d.pos[0][a].upload(*current[a], d.compute);
    d.pos[2][a].upload(*previous[a], d.compute);  // generation cur - 1
    d.pos[1][a].upload(*current[a], d.compute);   // scratch, overwritten by the next step
  }
  d.inv_mass.upload(state.inv_mass, d.compute);
  d.mass_host = state.mass, d.inv_mass_host = state.inv_mass;
  CTSURG_CUDA_CHECK(cudaStreamSynchronize(d.compute));  // the host vectors may go away after return
  d.drop_graph();
  particles = state.count();
}

void DeviceSimulation::Impl::upload_grid(const SpringGridModel& model, const ParticleState& state) {
  Device& d = *device;
  release_grab(-1);
  surface_vertices = -1, frames_queued = 0;
  upload_state(state);
  d.neighbours.upload(model.neighbours, d.compute);
  d.spring_mask.upload(model.spring_mask, d.compute);
  d.grid = model.view();
  d.grid.neighbours = d.neighbours.data();
  d.grid.spring_mask = d.spring_mask.data();
  d.grid.chunk_offsets = nullptr;
  CTSURG_CUDA_CHECK(cudaStreamSynchronize(d.compute));
  kind = UploadedModel::grid;
  springs = 0;
  spring_damping = std::any_of(model.damping.begin(), model.damping.end(), [](Real v) { return v > 0; });
}

void DeviceSimulation::Impl::upload_explicit(const ExplicitSpringModel& model, const ParticleState& state) {
  Device& d = *device;
  release_grab(-1);
  surface_vertices = -1, frames_queued = 0;
  upload_state(state);
  d.row_offsets.upload(model.row_offsets, d.compute);
  d.row_neighbour.upload(model.row_neighbour, d.compute);
  d.row_spring.upload(model.row_spring, d.compute);
  d.spring_ends.upload(model.spring_ends, d.compute);
  d.stiffness.upload(model.stiffness, d.compute);
  d.rest_length.upload(model.rest_length, d.compute);
  d.damping.upload(model.damping, d.compute);
  d.alive.upload(model.alive, d.compute);
  ExplicitSpringView v{};
  v.row_offsets = d.row_offsets.data(), v.row_neighbour = d.row_neighbour.data(), v.row_spring = d.row_spring.data();
  v.stiffness = d.stiffness.data(), v.rest_length = d.rest_length.data(), v.damping = d.damping.data();
  v.alive = d.alive.data();
  v.count = model.particle_count();
  v.chunk_start = nullptr;  // rows only: explicit_spring_forces, the CPU's per-particle path
  d.springs = v;
  CTSURG_CUDA_CHECK(cudaStreamSynchronize(d.compute));
  kind = UploadedModel::explicit_springs;
  springs = model.spring_count();
  spring_damping = model.spring_damping;
}

void DeviceSimulation::Impl::step(int64_t steps, const VerletConstants& c) {
  Device& d = *device;
  CTSURG_CUDA_CHECK(cudaSetDevice(d.ordinal));
  const bool grab = d.any_grab();  // the graph is dropped whenever the grab set changes
  int64_t left = steps;
  if (kGraphSteps > 0 && left >= kGraphSteps) {
    while (d.cur != 0 && left > 0) d.launch_step(kind, spring_damping, c, d.compute), --left;
    const bool same = d.graph != nullptr && d.graph_grab == grab && d.graph_constants.dt2 == c.dt2 &&
                      d.graph_constants.inv_dt == c.inv_dt && d.graph_constants.keep == c.keep &&
                      d.graph_constants.gx == c.gx && d.graph_constants.gy == c.gy && d.graph_constants.gz == c.gz;
    if (left >= kGraphSteps && !same) {
      d.drop_graph();
      cudaGraph_t graph = nullptr;
      CTSURG_CUDA_CHECK(cudaStreamBeginCapture(d.compute, cudaStreamCaptureModeThreadLocal));
      try {
        for (int64_t k = 0; k < kGraphSteps; ++k) d.launch_step(kind, spring_damping, c, d.compute);
      } catch (...) {
        (void)cudaStreamEndCapture(d.compute, &graph);
        if (graph != nullptr) (void)cudaGraphDestroy(graph);
        throw;
      }
      CTSURG_CUDA_CHECK(cudaStreamEndCapture(d.compute, &graph));
      const cudaError_t made = cudaGraphInstantiate(&d.graph, graph, 0);
      CTSURG_CUDA_CHECK(cudaGraphDestroy(graph));
      CTSURG_CUDA_CHECK(made);
      d.graph_constants = c, d.graph_grab = grab;
      // Capturing recorded the launches without running them; the rotation it did is a whole cycle.
    }
    for (; left >= kGraphSteps; left -= kGraphSteps) CTSURG_CUDA_CHECK(cudaGraphLaunch(d.graph, d.compute));
  }
  for (; left > 0; --left) d.launch_step(kind, spring_damping, c, d.compute);
}

void DeviceSimulation::Impl::normals(const VerletConstants& c, ParticleNormals& out) {
  Device& d = *device;
  CTSURG_CUDA_CHECK(cudaSetDevice(d.ordinal));
  const ParticleStateView s = d.state_view();  // writes the next generation (scratch), no rotation
  for (auto& n : d.normal) n.resize(static_cast<std::size_t>(particles));
  Real* n[3] = {d.normal[0].data(), d.normal[1].data(), d.normal[2].data()};
  const int blocks = blocks_for(particles);
  if (blocks > 0) {
    if (kind == UploadedModel::grid) {
      if (spring_damping)
        grid_step_kernel<true, true><<<blocks, kBlock, 0, d.compute>>>(d.grid, s, c, n[0], n[1], n[2]);
      else
        grid_step_kernel<false, true><<<blocks, kBlock, 0, d.compute>>>(d.grid, s, c, n[0], n[1], n[2]);
    } else {
      if (spring_damping)
        explicit_step_kernel<true, true><<<blocks, kBlock, 0, d.compute>>>(d.springs, s, c, n[0], n[1], n[2]);
      else
        explicit_step_kernel<false, true><<<blocks, kBlock, 0, d.compute>>>(d.springs, s, c, n[0], n[1], n[2]);
    }
    CTSURG_CUDA_LAUNCHED(d.compute);
  }
  std::vector<Real>* host[3] = {&out.x, &out.y, &out.z};
  for (int a = 0; a < 3; ++a) {
    host[a]->resize(static_cast<std::size_t>(particles));
    d.normal[a].download(host[a]->data(), host[a]->size(), d.compute);
  }
  CTSURG_CUDA_CHECK(cudaStreamSynchronize(d.compute));
}

int64_t DeviceSimulation::Impl::probe(const SphereView& tool) {
  Device& d = *device;
  CTSURG_CUDA_CHECK(cudaSetDevice(d.ordinal));
  d.zero_counter();
  if (particles > 0) {
    probe_kernel<<<blocks_for(particles), kBlock, 0, d.compute>>>(d.x(0), d.x(1), d.x(2), d.inv_mass.data(), particles,
                                                                  tool, d.counter.data());
    CTSURG_CUDA_LAUNCHED(d.compute);
  }
  return static_cast<int64_t>(d.read_counter());
}

Grab DeviceSimulation::Impl::grab(const SphereView& tool, int* handle) {
  Device& d = *device;
  CTSURG_CUDA_CHECK(cudaSetDevice(d.ordinal));
  d.flags.resize(static_cast<std::size_t>(particles));
  std::vector<uint8_t> inside(static_cast<std::size_t>(particles));
  if (particles > 0) {
    grabbable_kernel<<<blocks_for(particles), kBlock, 0, d.compute>>>(d.x(0), d.x(1), d.x(2), d.inv_mass.data(),
                                                                      particles, tool, d.flags.data());
    CTSURG_CUDA_LAUNCHED(d.compute);
    d.flags.download(inside.data(), inside.size(), d.compute);
    CTSURG_CUDA_CHECK(cudaStreamSynchronize(d.compute));
  }
  d.drop_graph();  // a captured graph holds the grab set it was recorded with
  Grab g;  // compaction in id order, as on the CPU: deterministic
  for (int32_t i = 0; i < particles; ++i)
    if (inside[static_cast<std::size_t>(i)]) g.particles.push_back(i);
  g.offsets.resize(3 * g.particles.size());
  std::size_t k = 0;  // the lowest free slot
  while (k < d.grabs.size() && d.grabs[k]->held) ++k;
  if (k == d.grabs.size()) {
    d.grabs.push_back(std::make_unique<Device::GrabSlot>());
    d.grabs.back()->centre.resize(1);
    grabs_held.push_back(0);
  }
  Device::GrabSlot& slot = *d.grabs[k];
  slot.count = static_cast<int64_t>(g.particles.size());
  slot.ids.upload(g.particles, d.compute);
  slot.offsets.resize(g.offsets.size());
  if (slot.count > 0) {
    grab_offsets_kernel<<<blocks_for(slot.count), kBlock, 0, d.compute>>>(d.x(0), d.x(1), d.x(2), slot.ids.data(),
                                                                          slot.count, tool, slot.offsets.data());
    CTSURG_CUDA_LAUNCHED(d.compute);
    slot.offsets.download(g.offsets.data(), g.offsets.size(), d.compute);
  }
  // Until apply_grab() moves it, the grab holds its particles where they are (centre at grab time).
  set_centre_kernel<<<1, 1, 0, d.compute>>>(slot.centre.data(), tool);
  CTSURG_CUDA_LAUNCHED(d.compute);
  CTSURG_CUDA_CHECK(cudaStreamSynchronize(d.compute));
  slot.held = true;
  grabs_held[k] = 1;
  if (handle != nullptr) *handle = static_cast<int>(k);
  return g;
}

void DeviceSimulation::Impl::apply_grab(int handle, const SphereView& centre) {
  Device& d = *device;
  CTSURG_CUDA_CHECK(cudaSetDevice(d.ordinal));
  Device::GrabSlot& slot = *d.grabs[static_cast<std::size_t>(handle)];
  set_centre_kernel<<<1, 1, 0, d.compute>>>(slot.centre.data(), centre);  // queued: no wait
  CTSURG_CUDA_LAUNCHED(d.compute);
  if (slot.count > 0) {
    place_grabbed_kernel<<<blocks_for(slot.count), kBlock, 0, d.compute>>>(d.x(0), d.x(1), d.x(2), slot.ids.data(),
                                                                          slot.offsets.data(), slot.count,
                                                                          slot.centre.data());
    CTSURG_CUDA_LAUNCHED(d.compute);
  }
}

void DeviceSimulation::Impl::release_grab(int handle) {
  for (std::size_t k = 0; k < grabs_held.size(); ++k) {
    if (handle >= 0 && static_cast<std::size_t>(handle) != k) continue;
    grabs_held[k] = 0;
    if (device != nullptr && k < device->grabs.size()) device->grabs[k]->held = false;
  }
  if (device != nullptr) device->drop_graph();  // the next step() captures a graph without it
}

int64_t DeviceSimulation::Impl::cut(const TriangleView& blade) {
  Device& d = *device;
  CTSURG_CUDA_CHECK(cudaSetDevice(d.ordinal));
  d.zero_counter();
  if (kind == UploadedModel::grid) {
    if (particles > 0) {
      cut_grid_kernel<<<blocks_for(particles), kBlock, 0, d.compute>>>(d.grid, d.spring_mask.data(), d.x(0), d.x(1),
                                                                       d.x(2), blade, d.counter.data());
      CTSURG_CUDA_LAUNCHED(d.compute);
    }
    return static_cast<int64_t>(d.read_counter()) / 2;  // both particles of a cut spring clear their bit
  }
  if (springs > 0) {
    cut_explicit_kernel<<<blocks_for(springs), kBlock, 0, d.compute>>>(d.spring_ends.data(), d.alive.data(), springs,
                                                                       d.x(0), d.x(1), d.x(2), blade, d.counter.data());
    CTSURG_CUDA_LAUNCHED(d.compute);
  }
  return static_cast<int64_t>(d.read_counter());
}

void DeviceSimulation::Impl::set_surface(const int32_t* surface_particles, const Real* weights, const Real* rest_vertices,
                                         int64_t vertices, const Real* rest_positions) {
  Device& d = *device;
  CTSURG_CUDA_CHECK(cudaSetDevice(d.ordinal));
  CTSURG_CUDA_CHECK(cudaStreamSynchronize(d.copy));  // no copy reads the old frames
  CTSURG_CUDA_CHECK(cudaStreamSynchronize(d.compute));
  const auto v = static_cast<std::size_t>(vertices);
  d.surface_particles.upload(surface_particles, 8 * v, d.compute);
  d.surface_weights.upload(weights, 8 * v, d.compute);
  d.surface_rest.upload(rest_vertices, 3 * v, d.compute);
  d.rest_positions.upload(rest_positions, 3 * static_cast<std::size_t>(particles), d.compute);
  const std::size_t n = 3 * v;
  for (int k = 0; k < 2; ++k) {
    d.vertices[k].resize(n);
    if (d.frame[k] != nullptr) CTSURG_CUDA_CHECK(cudaFreeHost(d.frame[k]));
    d.frame[k] = nullptr;
    if (n > 0) CTSURG_CUDA_CHECK(cudaMallocHost(reinterpret_cast<void**>(&d.frame[k]), n * sizeof(float)));
  }
  CTSURG_CUDA_CHECK(cudaStreamSynchronize(d.compute));
  surface_vertices = vertices;
  frames_queued = 0;
}

void DeviceSimulation::Impl::move_surface_async() {
  Device& d = *device;
  CTSURG_CUDA_CHECK(cudaSetDevice(d.ordinal));
  const int slot = static_cast<int>(frames_queued % 2);
  // The slot's previous copy must be done before its device buffer is written again (no-op the first
  // time: an event never recorded counts as complete).
  CTSURG_CUDA_CHECK(cudaStreamWaitEvent(d.compute, d.copy_done[slot], 0));
  const SurfaceCouplingView v{d.surface_particles.data(), d.surface_weights.data(), d.surface_rest.data(),
                              d.x(0), d.x(1), d.x(2), d.rest_positions.data(), d.vertices[slot].data(),
                              surface_vertices};
  if (surface_vertices > 0) {
    move_surface_kernel<<<blocks_for(surface_vertices), kBlock, 0, d.compute>>>(v);
    CTSURG_CUDA_LAUNCHED(d.compute);
  }
  CTSURG_CUDA_CHECK(cudaEventRecord(d.kernel_done[slot], d.compute));
  CTSURG_CUDA_CHECK(cudaStreamWaitEvent(d.copy, d.kernel_done[slot], 0));
  d.vertices[slot].download(d.frame[slot], d.vertices[slot].size(), d.copy);
  CTSURG_CUDA_CHECK(cudaEventRecord(d.copy_done[slot], d.copy));
  ++frames_queued;
}

std::span<const float> DeviceSimulation::Impl::wait_surface() {
  Device& d = *device;
  const int slot = static_cast<int>((frames_queued - 1) % 2);
  CTSURG_CUDA_CHECK(cudaEventSynchronize(d.copy_done[slot]));
  return {d.frame[slot], d.vertices[slot].size()};
}

void DeviceSimulation::Impl::download_state(ParticleState& state) const {
  const Device& d = *device;
  CTSURG_CUDA_CHECK(cudaSetDevice(d.ordinal));
  const auto n = static_cast<std::size_t>(particles);
  std::vector<Real>* current[3] = {&state.x, &state.y, &state.z};
  std::vector<Real>* previous[3] = {&state.px, &state.py, &state.pz};
  const int prev = (d.cur + 2) % 3;
  for (int a = 0; a < 3; ++a) {
    current[a]->resize(n), previous[a]->resize(n);
    d.pos[d.cur][a].download(current[a]->data(), n, d.compute);
    d.pos[prev][a].download(previous[a]->data(), n, d.compute);
  }
  CTSURG_CUDA_CHECK(cudaStreamSynchronize(d.compute));
  state.nx = state.x, state.ny = state.y, state.nz = state.z;  // scratch, as a fresh state has
  state.mass = d.mass_host, state.inv_mass = d.inv_mass_host;
}

void DeviceSimulation::Impl::download_grid_masks(uint32_t* masks) const {
  const Device& d = *device;
  CTSURG_CUDA_CHECK(cudaSetDevice(d.ordinal));
  d.spring_mask.download(masks, static_cast<std::size_t>(particles), d.compute);
  CTSURG_CUDA_CHECK(cudaStreamSynchronize(d.compute));
}

void DeviceSimulation::Impl::download_alive(uint8_t* alive) const {
  const Device& d = *device;
  CTSURG_CUDA_CHECK(cudaSetDevice(d.ordinal));
  d.alive.download(alive, static_cast<std::size_t>(springs), d.compute);
  CTSURG_CUDA_CHECK(cudaStreamSynchronize(d.compute));
}

void DeviceSimulation::Impl::synchronize() const {
  CTSURG_CUDA_CHECK(cudaSetDevice(device->ordinal));
  CTSURG_CUDA_CHECK(cudaStreamSynchronize(device->compute));
  CTSURG_CUDA_CHECK(cudaStreamSynchronize(device->copy));
}

}  // namespace ctsurg::sim
