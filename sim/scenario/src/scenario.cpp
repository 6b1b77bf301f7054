#include "ctsurg/sim/scenario/scenario.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/input_file.h"
#include "ctsurg/sim/scenario/scenario_model.h"
#include "scenario_material.h"
#include "sections/scenario_sections.h"
#include "yaml_field.h"

#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

namespace ctsurg::sim {

namespace fs = std::filesystem;

const char* to_string(ModelKind kind) {
  return kind == ModelKind::spring_grid ? "spring_grid" : kind == ModelKind::fem ? "fem" : kind == ModelKind::vessel ? "vessel" : "explicit_springs";
}

std::string describe_scenario(const Scenario& s) {
  nlohmann::json j;
  j["name"] = s.name;
  j["model"] = to_string(s.model);
  if (s.model == ModelKind::fem) {
    j["material_law"] = fem_law_name(s.material_law);
    j["solver"] = s.fem_solver == FemSolver::dynamic ? "dynamic" : s.fem_solver == FemSolver::implicit ? "implicit" : "static";
    j["elements"] = s.fem_order == 2 ? "quadratic" : "linear";
  }
  if (s.model == ModelKind::vessel) {
    j["skinning"] = s.vessel.skinning == VesselSkinning::rmf ? "rmf" : "spokes";
    j["spokes"] = s.vessel.spokes;
  }
  nlohmann::json inputs = nlohmann::json::object();
  const ModelInputs read = model_inputs(s);
  if (read.grid) inputs["grid"] = s.grid.string();
  if (read.tetmesh) inputs["tetmesh"] = s.tetmesh.string();
  if (read.surface) inputs["surface"] = s.surface.string();
  if (read.centerline) inputs["centerline"] = s.centerline.string();
  j["inputs"] = inputs;
  nlohmann::json instruments = nlohmann::json::array();  // files the run reads besides the stage outputs
  for (const auto& tool : s.tools) {
    if (tool.type->record == ToolRecord::instrument) instruments.push_back(tool.instrument_mesh.string());
  }
  j["instruments"] = instruments;
  j["trajectory"] = s.trajectory.string();
  nlohmann::json render = nlohmann::json::array();
  for (const auto& r : s.render) {
    render.push_back({{"name", r.name}, {"layout", r.layout}, {"frames", r.frames}, {"view", r.view}, {"size", r.size},
                      {"reference", r.reference}});
  }
  j["render"] = render;
  return j.dump(2);
}

static Scenario parse_fields(const std::string& text, const fs::path& file, const fs::path& base_dir) {
  const std::string name = file.string();
  YAML::Node doc;
  try {
    doc = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw InputError(name, "line " + std::to_string(e.mark.line + 1), "not valid YAML or JSON: " + e.msg);
  }
  const YamlField top(doc, "", &name);
  if (!top.is_map()) top.fail("a scenario is a map of sections (name, model, material, time, output, ...)");
  top.only({"ctsurg_scenario", "name", "model", "material", "gravity_mm_per_s2", "fixed", "tools", "contact", "time", "output",
            "render", "backend", "threads", "solver", "vessel"});
  Scenario s;
  s.file = file;
  if (top.child("ctsurg_scenario").integer(1, 1000) != 1) top.child("ctsurg_scenario").fail("this ctsurg reads version 1");
  s.name = top.has("name") ? top.child("name").text() : file.stem().string();
  // Each section by its own file (sections/scenario_sections.h), in the order of what they read.
  parse_model_section(top, base_dir, s);
  parse_material_section(top.child("material"), s);
  parse_vessel_section(top, s);
  if (top.has("gravity_mm_per_s2")) s.gravity = top.child("gravity_mm_per_s2").vec3();
  parse_fixed_section(top, s);
  parse_tools_section(top, base_dir, s);
  parse_time_section(top, s);
  parse_output_section(top, base_dir, s);
  parse_render_section(top, s);
  if (top.has("backend")) s.backend = top.child("backend").one_of({"cpu", "cuda", "auto"});
  if (top.has("threads")) s.threads = static_cast<int>(top.child("threads").integer(0, 1024));
  parse_contact_section(top, s);
  parse_solver_section(top, s);
  return s;
}

Scenario parse_scenario(const std::string& text, const fs::path& file, const fs::path& base_dir) {
  // The field checks read the document through yaml-cpp, which throws its own exceptions on shapes
  // they did not foresee (found by tests/fuzz/fuzz_scenario.cpp); every one is bad input.
  try {
    return parse_fields(text, file, base_dir);
  } catch (const YAML::Exception& e) {
    throw InputError(file.string(), "line " + std::to_string(e.mark.line + 1), "not a valid scenario: " + e.msg);
  }
}

std::string read_scenario_text(const fs::path& path) {
  check_input_file(path);
  if (fs::file_size(path) > (1u << 20)) throw InputError(path.string(), "", "more than 1 MiB: not a scenario file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string(), "(file)", "cannot be opened");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

Scenario read_scenario_file(const fs::path& path) { return parse_scenario(read_scenario_text(path), path, path.parent_path()); }

}  // namespace ctsurg::sim
