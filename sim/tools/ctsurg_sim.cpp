// ctsurg-sim SCENARIO.yaml: runs a surgical rehearsal scenario (a model of the tissue: spring-mass on
// the voxel grid or on explicit springs, or tetrahedral FEM; its fixed regions; a timeline of grab,
// probe, cut and force tools) and writes the trajectory: the surface at each output frame, per-frame
// metrics and the tools, as an HDF5 file with an XDMF sidecar for ParaView. See docs/sim.md and
// data_samples/scenarios/.
#include "ctsurg/core/atomic_output.h"
#include "ctsurg/core/error.h"
#include "ctsurg/core/progress_bar.h"
#include "ctsurg/core/provenance.h"
#include "ctsurg/core/tool_app.h"
#include "ctsurg/core/trajectory_file.h"
#include "ctsurg/core/version.h"
#include "ctsurg/core/xdmf_sidecar.h"
#include "ctsurg/sim/scenario/scenario.h"
#include "ctsurg/sim/scenario/scenario_model.h"
#include "ctsurg/sim/scenario/scenario_run.h"
#include "scenario_options.h"

#include <spdlog/spdlog.h>

#include <cstdio>
#include <memory>

namespace fs = std::filesystem;

int main(int argc, char** argv) {
  std::string scenario_path, output;
  ctsurg::sim::ScenarioOverrides overrides;
  bool describe = false, force = false;
  // Longer runs ask for --force: an hour of this machine, estimated from the run's first second.
  constexpr double kMaxWallS = 3600;
  return ctsurg::run_tool(
      argc, argv, "ctsurg-sim",
      "Runs a scenario file (YAML or JSON): a model of the tissue (spring-mass on the implicit 18-neighbour grid "
      "or on explicit springs; tetrahedral FEM: linear, St. Venant-Kirchhoff or Neo-Hookean, dynamic or "
      "quasi-static), fixed regions and a timeline of grab, probe, cut and force tools, on the CPU or a CUDA "
      "device. Writes the trajectory (surface per output frame, metrics, tools; HDF5 + XDMF). Paths in the "
      "scenario are relative to its folder; the options below override them.",
      [&](CLI::App& app) {
        app.add_option("scenario", scenario_path, "Scenario file (.yaml, .yml or .json)")->required();
        app.add_option("-o,--output", output, "Trajectory to write (.h5); default: the scenario's output.trajectory");
        overrides.declare(app);
        app.add_flag("--describe", describe,
                     "Print what the scenario reads and writes (model, input files, trajectory, render requests) as JSON "
                     "and exit without running; for the pipeline (scripts/Makefile)");
        app.add_flag("--force", force,
                     "Run even when the run is estimated (from its first second) to take more than an hour");
      },
      [&](const ctsurg::ToolContext& ctx) {
        ctsurg::sim::Scenario s = ctsurg::sim::read_scenario_file(scenario_path);
        if (!output.empty()) s.trajectory = output;
        overrides.apply(s);
        if (describe) {
          std::printf("%s\n", ctsurg::sim::describe_scenario(s).c_str());
          return;
        }
        if (s.trajectory.extension() != ".h5") {
          throw ctsurg::InputError(s.trajectory.string(), "output.trajectory", "the trajectory is an HDF5 file: name it *.h5");
        }
        // The output is checked before simulating, so a bad path costs nothing.
        const ctsurg::sim::ModelInputs read = ctsurg::sim::model_inputs(s);
        std::vector<fs::path> inputs{scenario_path};
        if (read.grid) inputs.push_back(s.grid);
        if (read.surface) inputs.push_back(s.surface);
        if (read.tetmesh) inputs.push_back(s.tetmesh);
        if (read.centerline) inputs.push_back(s.centerline);
        ctsurg::check_output_paths({s.trajectory, ctsurg::xdmf_path_for(s.trajectory)}, inputs);
        spdlog::info("sim: scenario '{}' ({}), {} s, {} tool(s)", s.name, ctsurg::sim::to_string(s.model), s.duration_s,
                     s.tools.size());
        std::unique_ptr<ctsurg::ProgressBar> bar;
        ctsurg::sim::RunReport report;
        uint64_t shown = 0;
        const ctsurg::sim::RunBudget budget{force ? 0.0 : kMaxWallS};
        const ctsurg::Trajectory traj = ctsurg::sim::run_scenario(
            s, &report,
            [&](double fraction) {
              if (!bar) bar = std::make_unique<ctsurg::ProgressBar>("simulating", 1000);
              const uint64_t now = static_cast<uint64_t>(fraction * 1000);
              if (now > shown) bar->advance(now - shown);
              shown = std::max(shown, now);
            },
            budget);
        bar.reset();
        for (const auto& note : report.notes) spdlog::info("sim: {}", note);
        const double rate = report.wall_s > 0 ? report.steps / report.wall_s : 0.0;
        const std::string fixed = std::to_string(report.fixed) + " fixed" +
                                  (report.partly_fixed ? ", " + std::to_string(report.partly_fixed) + " held in some axes" : "");
        if (s.model != ctsurg::sim::ModelKind::fem) {
          spdlog::info("sim: {} particles ({}), {} springs; dt {:.3g} s (critical {:.3g} s), {} steps in {:.2f} s ({:.0f} steps/s)",
                       report.particles, fixed, report.springs, report.dt_s, report.critical_dt_s, report.steps, report.wall_s,
                       rate);
        } else if (s.fem_solver == ctsurg::sim::FemSolver::dynamic) {
          spdlog::info("sim: {} nodes ({}), {} tets; dt {:.3g} s (critical {:.3g} s), {} steps in {:.2f} s ({:.0f} steps/s)",
                       report.particles, fixed, report.elements, report.dt_s, report.critical_dt_s, report.steps,
                       report.wall_s, rate);
        } else {
          spdlog::info("sim: {} nodes ({}), {} tets; static equilibrium per frame, {} Newton iterations in {:.2f} s",
                       report.particles, fixed, report.elements, report.steps, report.wall_s);
        }
        if (report.springs_cut > 0) {
          spdlog::info("sim: {} {} cut, {} surface triangles removed", report.springs_cut,
                       s.model == ctsurg::sim::ModelKind::fem ? "element faces" : "springs", report.surface_triangles_removed);
        }
        ctsurg::Provenance provenance{ctx.name, ctsurg::kVersion, ctx.command_line, {}, nlohmann::json::array()};
        provenance.add_input(scenario_path);
        if (read.grid) provenance.add_input(s.grid);
        if (read.surface) provenance.add_input(s.surface);
        if (read.tetmesh) provenance.add_input(s.tetmesh);
        if (read.centerline) provenance.add_input(s.centerline);
        ctsurg::write_trajectory_file(s.trajectory, traj, provenance);
        spdlog::info("sim: wrote {} ({} frames, {} vertices)", s.trajectory.string(), traj.frame_count(), traj.vertex_count());
      });
}
