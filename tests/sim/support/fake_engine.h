// A simulation engine with no physics, for testing what drives engines (the scenario runner, the
// trajectory recorder): two nodes at rest at (0, 0, 0) and (1, 0, 0) mm of its local frame, the second
// moved to x = 1 + time (mm, s); it records every call it gets, reports itself unstable while its step
// is above `unstable_above_dt` (from `unstable_after_s` on), and can restart with half the step.
#pragma once

#include "ctsurg/sim/base/simulation_engine.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

namespace ctsurg::sim::test {

class FakeEngine final : public SimulationEngine {
 public:
  struct Call {
    std::string what;   // "step" or "equilibrium"
    double time = 0;    // the engine's time after the call
    int steps = 0;      // step: how many
    std::vector<ToolInput> tools;
  };

  FakeEngine(double dt, bool quasi_static = false) : dt_(quasi_static ? 0 : dt), quasi_static_(quasi_static) {}

  double unstable_above_dt = 1e300;
  double unstable_after_s = 0;
  bool batches = false;
  std::vector<size_t> engaged_tools;
  std::shared_ptr<std::vector<Call>> calls = std::make_shared<std::vector<Call>>();  // shared: outlives a run
  int checks = 0;

  EngineCounts counts() const override { return {.nodes = 2, .fixed = 1, .springs = 1, .elements = 0, .critical_dt_s = 2 * dt_}; }
  const Vec3& origin() const override { return origin_; }
  const std::vector<double>& rest_positions() const override { return rest_; }
  bool has_surface() const override { return false; }
  std::vector<std::pair<std::string, std::string>> extra_metrics() const override { return {{"calls", "1"}}; }
  double blade_sweep_mm() const override { return 0.5; }
  bool quasi_static() const override { return quasi_static_; }
  double dt() const override { return dt_; }
  double time() const override { return time_; }
  int64_t steps() const override { return steps_; }
  bool batches_steps() const override { return batches; }
  StabilityReport step(const std::vector<ToolInput>& tools, int steps) override {
    for (int k = 0; k < steps; ++k) time_ += dt_;
    steps_ += steps;
    calls->push_back({"step", time_, steps, tools});
    return {};
  }
  void equilibrium(const std::vector<ToolInput>& tools, double time) override {
    time_ = time;
    ++steps_;
    calls->push_back({"equilibrium", time_, 0, tools});
  }
  void sync() override {}
  void positions(std::vector<double>& xyz) const override { xyz = {0, 0, 0, 1 + time_, 0, 0}; }
  void surface_vertices(std::vector<float>& xyz) override {
    std::vector<double> p;
    positions(p);
    xyz.assign(p.begin(), p.end());
  }
  const std::vector<uint32_t>& triangles() const override { return no_triangles_; }
  const std::vector<Real>& surface_rest_vertices() const override { return no_vertices_; }
  EngineMetrics metrics() const override {
    EngineMetrics m;
    m.kinetic_energy = 1;
    m.elastic_energy = 2;
    m.max_displacement = time_;
    m.extra = {static_cast<double>(calls->size())};
    return m;
  }
  bool engaged(size_t tool) const override {
    return std::find(engaged_tools.begin(), engaged_tools.end(), tool) != engaged_tools.end();
  }
  StabilityReport check_stability() override {
    ++checks;
    StabilityReport r;
    if (dt_ > unstable_above_dt && time_ >= unstable_after_s) {
      r.stable = false;
      r.time = time_;
      r.message = "fake: dt " + std::to_string(dt_) + " too large";
    }
    return r;
  }
  bool can_restart() const override { return true; }
  void save_checkpoint() override { saved_ = {time_, static_cast<double>(steps_)}; }
  void restart_halved() override {
    time_ = saved_[0];
    steps_ = static_cast<int64_t>(saved_[1]);
    dt_ /= 2;
  }

 private:
  Vec3 origin_{100, 200, 300};
  std::vector<double> rest_{0, 0, 0, 1, 0, 0};
  std::vector<uint32_t> no_triangles_;
  std::vector<Real> no_vertices_;
  double dt_;
  bool quasi_static_;
  double time_ = 0;
  int64_t steps_ = 0;
  std::array<double, 2> saved_{0, 0};
};

}  // namespace ctsurg::sim::test
