// The command-line options with which ctsurg-sim and ctsurg-live override a scenario file's model
// inputs, backend and threads (one declaration, so both tools take the same options the same way).
#pragma once

#include "ctsurg/sim/scenario/scenario.h"

#include <CLI/CLI.hpp>

#include <string>

namespace ctsurg::sim {

struct ScenarioOverrides {
  std::string grid, surface, tetmesh, centerline, backend;
  int threads = -1;

  void declare(CLI::App& app) {
    app.add_option("--grid", grid, "Occupancy grid file (overrides model.grid)");
    app.add_option("--surface", surface, "Surface file (overrides model.surface)");
    app.add_option("--tetmesh", tetmesh, "Tet mesh file (overrides model.tetmesh)");
    app.add_option("--centerline", centerline, "Centerline file (overrides model.centerline; kind vessel)");
    app.add_option("--backend", backend, "cpu, cuda or auto (overrides backend)")->check(CLI::IsMember({"cpu", "cuda", "auto"}));
    app.add_option("--threads", threads, "CPU threads, 0 = automatic (overrides threads)")->check(CLI::Range(0, 1024));
  }

  void apply(Scenario& s) const {
    if (!grid.empty()) s.grid = grid;
    if (!surface.empty()) s.surface = surface;
    if (!tetmesh.empty()) s.tetmesh = tetmesh;
    if (!centerline.empty()) s.centerline = centerline;
    if (!backend.empty()) s.backend = backend;
    if (threads >= 0) s.threads = threads;
  }
};

}  // namespace ctsurg::sim
