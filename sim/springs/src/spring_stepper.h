// Where a SpringEngine's state is stepped (spring_engine.h): on the host with the CPU kernels, or on a
// CUDA device (DeviceSimulation, device_simulation.h) with the same kernels. The engine keeps the model
// and a ParticleState on the host either way; the device stepper copies the state back when the engine
// needs it there (output frames, stability checks, surface cuts) and copies it up after the host
// changed it.
#pragma once

#include "ctsurg/core/error.h"
#include "ctsurg/sim/base/particle_state.h"
#include "ctsurg/sim/springs/device_simulation.h"
#include "ctsurg/sim/springs/explicit_spring_model.h"
#include "ctsurg/sim/springs/instrument_contact.h"
#include "ctsurg/sim/springs/sphere_tools.h"
#include "ctsurg/sim/springs/spring_cutting.h"
#include "ctsurg/sim/springs/spring_engine.h"
#include "ctsurg/sim/springs/spring_grid_model.h"
#include "ctsurg/sim/springs/spring_mass_step.h"

#include <array>
#include <memory>
#include <variant>

namespace ctsurg::sim {

class SpringStepper {
 public:
  virtual ~SpringStepper() = default;
  virtual void step(const StepParameters& parameters) = 0;
  // Captures the particles inside the sphere (a grab when `hold`, or the particles a force acts on);
  // a held grab's handle goes to *handle for apply_grab and release_grab.
  virtual Grab capture(const Sphere& tool, bool hold, int* handle) = 0;
  virtual void apply_grab(const Grab& grab, int handle, const std::array<double, 3>& centre) = 0;
  virtual void release_grab(int handle) = 0;
  virtual int64_t probe(const Sphere& tool) = 0;
  virtual int64_t push_out(const InstrumentView& instrument) = 0;
  virtual int64_t cut(const Triangle& blade) = 0;
  // Makes the host's state (and the model's spring presence) current / uploads the host's state.
  virtual void to_host() = 0;
  virtual void from_host() = 0;
  virtual bool on_device() const = 0;
};

class HostSpringStepper final : public SpringStepper {
 public:
  HostSpringStepper(SpringModel& model, ParticleState& state, int threads) : model_(model), state_(state), threads_(threads) {}
  void step(const StepParameters& p) override {
    std::visit([&](const auto& m) { sim::step(m, state_, p); }, model_);
  }
  Grab capture(const Sphere& tool, bool, int*) override { return grab_particles_in_sphere(state_, tool, threads_); }
  void apply_grab(const Grab& grab, int, const std::array<double, 3>& centre) override {
    sim::apply_grab(state_, grab, centre, threads_);
  }
  void release_grab(int) override {}
  int64_t probe(const Sphere& tool) override { return probe_sphere(state_, tool, threads_); }
  int64_t push_out(const InstrumentView& instrument) override { return push_out_of_instrument(state_, instrument, threads_); }
  int64_t cut(const Triangle& blade) override {
    return std::visit([&](auto& m) { return cut_springs_crossing_triangle(m, state_, blade, threads_); }, model_);
  }
  void to_host() override {}
  void from_host() override {}
  bool on_device() const override { return false; }

 private:
  SpringModel& model_;
  ParticleState& state_;
  int threads_;
};

// Grabs are held on the device (DeviceSimulation's handles) and placed after every step there.
// CI has no GPU; run on an H100 on 2026-11-26 (docs/gpu.md).
class DeviceSpringStepper final : public SpringStepper {
 public:
  DeviceSpringStepper(SpringModel& model, ParticleState& state) : model_(model), state_(state) {
    std::visit([&](const auto& m) { gpu_.upload(m, state_); }, model_);
  }
  void step(const StepParameters& p) override { gpu_.step(1, p); }
  Grab capture(const Sphere& tool, bool hold, int* handle) override {
    int h = -1;
    Grab g = gpu_.grab(tool, &h);
    if (hold && handle != nullptr) *handle = h;
    if (!hold) gpu_.release_grab(h);
    return g;
  }
  void apply_grab(const Grab&, int handle, const std::array<double, 3>& centre) override { gpu_.apply_grab(centre, handle); }
  void release_grab(int handle) override { gpu_.release_grab(handle); }
  int64_t probe(const Sphere& tool) override { return gpu_.probe(tool); }
  // The scenario refuses instruments on cuda (scenario_engine.cpp) until the device launch exists.
  int64_t push_out(const InstrumentView&) override {
    throw InputError("instrument", "backend", "instruments run on the cpu backend only; set backend: cpu");
  }
  int64_t cut(const Triangle& blade) override { return gpu_.cut_springs_crossing_triangle(blade); }
  void to_host() override {
    gpu_.download_state(state_);
    std::visit([&](auto& m) { gpu_.download_springs(m); }, model_);
  }
  void from_host() override { gpu_.upload_state(state_); }
  bool on_device() const override { return true; }

 private:
  SpringModel& model_;
  ParticleState& state_;
  DeviceSimulation gpu_;
};

}  // namespace ctsurg::sim
