// ctsurg-live SCENARIO.yaml: a live rehearsal in a browser. Builds the scenario's model as ctsurg-sim
// does, starts a local web server and prints its URL; the page shows the organ (with its normal map)
// and lets the user grab, probe and cut it with the mouse or a touch screen while the server simulates
// in real time. A "save" from the page (or Ctrl-C with unsaved work) writes a scenario and its
// trajectory that ctsurg-sim replays to the same trajectory. See docs/live.md.
#include "ctsurg/core/error.h"
#include "ctsurg/core/atomic_output.h"
#include "ctsurg/core/surface_mesh_file.h"
#include "ctsurg/core/tool_app.h"
#include "ctsurg/mesh/gltf_material.h"
#include "ctsurg/sim/live/live_server.h"
#include "ctsurg/sim/scenario/scenario.h"
#include "ctsurg/sim/scenario/scenario_model.h"
#include "scenario_options.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>

namespace fs = std::filesystem;

namespace {

// The surface file's texture atlas and normal map for the page (RGBA8), when the session's surface is
// that file's (same vertex count).
void page_texture(const fs::path& surface_file, size_t vertex_count, ctsurg::sim::LiveServerOptions& o) {
  const ctsurg::SurfaceMesh mesh = ctsurg::read_surface_mesh_file(surface_file);
  if (mesh.uvs.empty() || static_cast<size_t>(mesh.vertex_count()) != vertex_count) {
    if (!mesh.uvs.empty()) {
      spdlog::warn("live: {} has {} vertices, the model's surface {}: the page shows it without the normal map",
                   surface_file.string(), mesh.vertex_count(), vertex_count);
    }
    return;
  }
  o.uvs = mesh.uvs;
  if (mesh.normal_map.empty()) return;
  const ctsurg::NormalMapImage& m = mesh.normal_map;
  o.normal_map_width = static_cast<int>(m.width);
  o.normal_map_height = static_cast<int>(m.height);
  o.normal_map_rgba.resize(4 * static_cast<size_t>(m.width * m.height));
  const double scale = 255.0 / ((1 << m.bits) - 1);
  for (size_t p = 0; p < static_cast<size_t>(m.width * m.height); ++p) {
    for (int c = 0; c < 3; ++c) o.normal_map_rgba[4 * p + c] = static_cast<uint8_t>(std::lround(m.rgb[3 * p + c] * scale));
    o.normal_map_rgba[4 * p + 3] = 255;
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::string scenario_path, save, trajectory;
  ctsurg::sim::ScenarioOverrides overrides;
  bool overwrite = false;
  ctsurg::sim::LiveServerOptions options;
  int port = 0;
  return ctsurg::run_tool(
      argc, argv, "ctsurg-live",
      "A live rehearsal in a browser: builds the scenario's model (as ctsurg-sim does: spring-mass, FEM, ...), "
      "starts a local web server and prints its URL. The page shows the organ and lets the user grab, probe and "
      "cut it with the mouse or a touch screen (keys: G grab, P probe, C cut, Space pause, R reset, S save) while "
      "the server simulates in real time. Save writes a scenario and its trajectory that ctsurg-sim replays to "
      "the same trajectory; Ctrl-C saves unsaved work, then stops. The scenario's own tools act as in a run.",
      [&](CLI::App& app) {
        app.add_option("scenario", scenario_path, "Scenario file (.yaml, .yml or .json): the model, material, fixed regions")->required();
        overrides.declare(app);
        app.add_option("--host", options.host,
                       "Address to listen on (default 127.0.0.1: this machine only). Another address lets other "
                       "machines in: anyone with the URL (its token) can then control the session");
        app.add_option("--port", port, "Port to listen on (0: any free port, printed)")->check(CLI::Range(0, 65535));
        app.add_option("--save", save,
                       "Scenario file a save writes (.yaml; default: SCENARIO-live-DATE-TIME.yaml in the current "
                       "folder); its trajectory goes beside it as .h5 unless --trajectory says otherwise");
        app.add_option("--trajectory", trajectory, "Trajectory file a save writes (.h5)");
        app.add_flag("--overwrite", overwrite, "Let a save replace existing files (otherwise refused before starting)");
        app.add_option("--picture-rate", options.picture_hz, "Pictures a second sent to the page (1 .. 240; default 60)")
            ->check(CLI::Range(1.0, 240.0));
        app.add_option("--realtime-factor", options.realtime_factor,
                       "Simulated seconds per wall second aimed at (default 1: real time)")
            ->check(CLI::Range(0.001, 100.0));
        app.add_option("--grab-radius", options.grab_radius_mm, "The page's grab radius to start with, mm (default 8)")
            ->check(CLI::Range(0.5, 50.0));
        app.add_option("--probe-radius", options.probe_radius_mm, "The page's probe radius to start with, mm (default 6)")
            ->check(CLI::Range(0.5, 50.0));
        app.add_option("--cut-depth", options.cut_depth_mm, "The page's cut depth to start with, mm (default 15)")
            ->check(CLI::Range(1.0, 150.0));
      },
      [&](const ctsurg::ToolContext&) {
        const std::string text = ctsurg::sim::read_scenario_text(scenario_path);  // read once: parsed, and kept for the save
        ctsurg::sim::Scenario s = ctsurg::sim::parse_scenario(text, scenario_path, fs::path(scenario_path).parent_path());
        overrides.apply(s);
        options.port = static_cast<uint16_t>(port);

        // Where a save goes: checked now, so a rehearsal never ends in a refused save. By default a new
        // name per session (the scenario's and the start time), so no earlier rehearsal is replaced.
        if (save.empty()) {
          const std::time_t now = std::time(nullptr);
          char stamp[32];
          std::strftime(stamp, sizeof stamp, "%Y%m%d-%H%M%S", std::localtime(&now));
          save = fs::path(scenario_path).stem().string() + "-live-" + stamp + ".yaml";
        }
        options.save_scenario = save;
        if (options.save_scenario.extension() != ".yaml" && options.save_scenario.extension() != ".yml") {
          throw ctsurg::InputError(options.save_scenario.string(), "--save", "a saved session is a YAML scenario: name it *.yaml");
        }
        options.save_trajectory = trajectory.empty() ? fs::path(options.save_scenario).replace_extension(".h5") : fs::path(trajectory);
        if (options.save_trajectory.extension() != ".h5") {
          throw ctsurg::InputError(options.save_trajectory.string(), "--trajectory", "the trajectory is an HDF5 file: name it *.h5");
        }
        options.save_scenario = fs::absolute(options.save_scenario);
        options.save_trajectory = fs::absolute(options.save_trajectory);
        const ctsurg::sim::ModelInputs read = ctsurg::sim::model_inputs(s);
        std::vector<fs::path> inputs{scenario_path};
        for (const auto& [needed, path] : {std::pair{read.grid, s.grid}, {read.surface, s.surface},
                                           {read.tetmesh, s.tetmesh}, {read.centerline, s.centerline}}) {
          if (needed) inputs.push_back(path);
        }
        ctsurg::check_output_paths({options.save_scenario, options.save_trajectory}, inputs);
        for (const fs::path& out : {options.save_scenario, options.save_trajectory}) {
          if (fs::exists(out) && !overwrite) {
            throw ctsurg::InputError(out.string(), "--save", "exists: choose another name, or --overwrite to let a save replace it");
          }
        }

        spdlog::info("live: building '{}' ({})", s.name, ctsurg::sim::to_string(s.model));
        ctsurg::sim::LiveSession session(s, text, [](const std::string& note) { spdlog::info("live: {}", note); });
        std::vector<float> lps;
        session.surface(lps);
        if (read.surface) page_texture(s.surface, lps.size() / 3, options);
        const auto colour = ctsurg::gltf_linear_colour(ctsurg::kGltfTissueOnScreen);
        options.colour = {colour[0], colour[1], colour[2]};
        char step[64] = "one equilibrium a frame";
        if (session.dt() > 0) std::snprintf(step, sizeof step, "step %.3g ms", session.dt() * 1e3);
        options.model_description = std::string(ctsurg::sim::to_string(s.model)) + ", " + std::to_string(lps.size() / 3) +
                                    " surface vertices, " + step;
        options.stop_on_signals = true;

        ctsurg::sim::LiveServer server(session, options, [](const std::string& line) { spdlog::info("{}", line); });
        std::printf("ctsurg-live: open this in a browser (Ctrl-C stops; unsaved work is saved first):\n  %s\n",
                    server.url().c_str());
        std::fflush(stdout);
        server.run();

        if (server.unsaved()) {
          try {
            session.save(options.save_scenario, options.save_trajectory);
            spdlog::info("live: saved the session to {} and {}", options.save_scenario.string(), options.save_trajectory.string());
          } catch (const ctsurg::InputError& e) {
            spdlog::warn("live: the session was not saved: {}", e.what());
          }
        }
        ctsurg::sim::LiveServerStats st = server.stats();
        spdlog::info("live: {} pictures sent ({:.1f} MB), {} messages ({} refused)", st.frames_sent,
                     st.frame_bytes_sent / 1e6, st.messages, st.refused_messages);
        if (!st.input_to_picture_ms.empty()) {
          std::vector<double>& ms = st.input_to_picture_ms;
          std::sort(ms.begin(), ms.end());
          spdlog::info("live: from a page's message to its picture on the socket: median {:.1f} ms, 95 % within {:.1f} ms ({} pictures)",
                       ms[ms.size() / 2], ms[std::min(ms.size() - 1, ms.size() * 95 / 100)], ms.size());
        }
      });
}
