#include "ctsurg/sim/scenario/scenario.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/input_file.h"
#include "ctsurg/sim/scenario/scenario_model.h"
#include "scenario_material.h"
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

namespace {

// One tool: exactly one key of the registry (tool_type.h), whose type reads its own section.
ToolAction tool_of(const YamlField& item, const ToolParseContext& context) {
  const std::string expected = "expected one of " + tool_type_names(":") + " with the tool's fields under it";
  if (!item.is_map()) item.fail(expected);
  const ToolType* type = nullptr;
  int kinds = 0;
  std::vector<std::string> names;
  for (const ToolType* t : tool_types()) {
    names.emplace_back(t->name);
    if (item.has(t->name)) {
      ++kinds;
      type = t;
    }
  }
  item.only(names);
  if (kinds != 1) item.fail("each tool is exactly one of " + tool_type_names(":"));
  ToolAction t;
  t.type = type;
  t.label = item.path() + " (" + type->name + ")";
  type->parse(item, context, t);
  return t;
}

FixedRegionSpec fixed_of(const YamlField& item) {
  item.only({"box", "box_fraction", "half_space", "label", "axes"});
  FixedRegionSpec r;
  int given = 0;
  const auto box_of = [&](const YamlField& b) {
    b.only({"min", "max"});
    Box box{b.child("min").vec3(), b.child("max").vec3()};
    for (int c = 0; c < 3; ++c) {
      if (box.min[static_cast<size_t>(c)] > box.max[static_cast<size_t>(c)]) b.child("max").fail("each max must be >= its min");
    }
    return box;
  };
  if (item.has("box")) {
    r.kind = FixedRegionSpec::Kind::box;
    r.box = box_of(item.child("box"));
    ++given;
  }
  if (item.has("box_fraction")) {
    r.kind = FixedRegionSpec::Kind::box_fraction;
    r.box = box_of(item.child("box_fraction"));
    ++given;
  }
  if (item.has("half_space")) {
    const YamlField h = item.child("half_space");
    h.only({"point_mm", "normal"});
    r.kind = FixedRegionSpec::Kind::half_space;
    r.half_space = {h.child("point_mm").vec3(), h.child("normal").vec3()};
    if (r.half_space.normal == std::array<double, 3>{0, 0, 0}) h.child("normal").fail("must not be zero");
    ++given;
  }
  if (item.has("label")) {
    r.kind = FixedRegionSpec::Kind::label;
    r.label = static_cast<uint16_t>(item.child("label").integer(1, 65535));
    ++given;
  }
  if (given != 1) item.fail("each fixed region is exactly one of box, box_fraction, half_space, label");
  if (item.has("axes")) {
    // Rollers and symmetry planes: only these components are held.
    r.axes = 0;
    const auto axes = item.child("axes").items();
    if (axes.empty()) item.child("axes").fail("name at least one of x, y, z");
    for (const auto& a : axes) {
      const std::string axis = a.one_of({"x", "y", "z"});
      const uint8_t bit = static_cast<uint8_t>(1u << (axis[0] - 'x'));
      if (r.axes & bit) a.fail("'" + axis + "' is named twice");
      r.axes |= bit;
    }
  }
  return r;
}

SolverSpec solver_of(const YamlField& f) {
  f.only({"linear", "tolerance_mm", "max_newton_iterations", "max_cg_iterations", "local_region"});
  SolverSpec s;
  if (f.has("linear")) {
    const std::string kind = f.child("linear").one_of({"auto", "direct", "iterative"});
    s.linear = kind == "direct" ? FemLinearSolve::direct : kind == "iterative" ? FemLinearSolve::iterative : FemLinearSolve::automatic;
  }
  if (f.has("tolerance_mm")) {
    s.tolerance_mm = f.child("tolerance_mm").positive();
    if (s.tolerance_mm > 10) f.child("tolerance_mm").fail("must be <= 10 mm (a budget, not a displacement)");
  }
  if (f.has("max_newton_iterations")) s.max_newton_iterations = static_cast<int>(f.child("max_newton_iterations").integer(1, 1000));
  if (f.has("max_cg_iterations")) s.max_cg_iterations = static_cast<int>(f.child("max_cg_iterations").integer(0, 100000000));
  if (f.has("local_region")) {
    const YamlField r = f.child("local_region");
    r.only({"radius_mm", "balance_iterations"});
    s.local_region_mm = r.child("radius_mm").positive();
    if (r.has("balance_iterations")) s.local_region_balance = static_cast<int>(r.child("balance_iterations").integer(0, 100));
  }
  return s;
}

}  // namespace

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

  const YamlField m = top.child("model");
  m.only({"kind", "grid", "surface", "tetmesh", "springs_from", "coupling", "mass_from_fraction", "material_law", "solver", "elements",
          "close_cuts", "centerline"});
  const std::string kind = m.child("kind").one_of({"spring_grid", "explicit_springs", "fem", "vessel"});
  s.model = kind == "spring_grid" ? ModelKind::spring_grid
            : kind == "fem"       ? ModelKind::fem
            : kind == "vessel"    ? ModelKind::vessel
                                  : ModelKind::explicit_springs;
  if (s.model == ModelKind::vessel) {
    // A vessel reads its centerline only and draws its own surface from it (sim/vessel).
    for (const char* other : {"grid", "surface", "tetmesh", "coupling", "mass_from_fraction"}) {
      if (m.has(other)) m.child(other).fail("not for kind: vessel (it reads the centerline only and draws its own surface)");
    }
    const std::string path = m.child("centerline").text();
    if (path.empty()) m.child("centerline").fail("must name a centerline file (ctsurg-centerline)");
    s.centerline = resolve_scenario_path(base_dir, path);
  } else if (m.has("centerline")) {
    m.child("centerline").fail("only for kind: vessel");
  }
  if ((s.model != ModelKind::fem && s.model != ModelKind::vessel) || m.has("grid")) s.grid = resolve_scenario_path(base_dir, m.child("grid").text());
  if (m.has("material_law")) {
    m.child("material_law").fail("the law moved to the material section: write `material: {law: " + m.child("material_law").text() +
                                 ", ...}` (docs/sim.md, \"Materials\")");
  }
  if (m.has("solver") && s.model != ModelKind::fem) m.child("solver").fail("only for kind: fem");
  if (m.has("solver")) {
    const std::string solver = m.child("solver").one_of({"dynamic", "static", "implicit"});
    s.fem_solver = solver == "static" ? FemSolver::static_equilibrium : solver == "implicit" ? FemSolver::implicit : FemSolver::dynamic;
  }
  if (m.has("elements")) {
    if (s.model != ModelKind::fem) m.child("elements").fail("only for kind: fem");
    s.fem_order = m.child("elements").one_of({"linear", "quadratic"}) == std::string("quadratic") ? 2 : 1;
    if (s.fem_order == 2 && s.fem_solver == FemSolver::dynamic)
      m.child("elements").fail("quadratic tets need solver: static or implicit (the explicit dynamics runs linear tets)");
  }
  if (m.has("surface")) s.surface = resolve_scenario_path(base_dir, m.child("surface").text());
  if (m.has("springs_from")) {
    if (s.model != ModelKind::explicit_springs) m.child("springs_from").fail("only for kind: explicit_springs");
    s.springs_from = m.child("springs_from").one_of({"grid", "tetmesh"}) == std::string("grid") ? SpringSource::grid
                                                                                               : SpringSource::tetmesh;
  }
  if (m.has("tetmesh")) s.tetmesh = resolve_scenario_path(base_dir, m.child("tetmesh").text());
  if (s.springs_from == SpringSource::tetmesh && s.tetmesh.empty()) m.child("tetmesh").fail("missing (springs_from: tetmesh)");
  if (s.model == ModelKind::fem && s.tetmesh.empty()) throw InputError(name, "model.tetmesh", "missing (kind: fem needs a tet mesh)");
  if (m.has("coupling")) {
    s.coupling = m.child("coupling").one_of({"trilinear", "nearest_particle"}) == std::string("trilinear")
                     ? CouplingMode::trilinear
                     : CouplingMode::nearest_particle;
  }
  if (m.has("mass_from_fraction")) s.mass_from_fraction = m.child("mass_from_fraction").boolean();
  if (m.has("close_cuts")) {
    if (s.model == ModelKind::fem || s.model == ModelKind::vessel)
      m.child("close_cuts").fail("only for the spring models (a FEM cut's surface is left open; a vessel caps its cuts)");
    s.close_cuts = m.child("close_cuts").boolean();
  }

  parse_material_section(top.child("material"), s);

  if (s.model == ModelKind::vessel) {
    const YamlField v = top.child("vessel");
    v.only({"wall_thickness_mm", "spokes", "skinning", "blood_filled", "newton_iterations"});
    s.vessel.wall_thickness_mm = v.child("wall_thickness_mm").positive();
    if (s.vessel.wall_thickness_mm > 50) v.child("wall_thickness_mm").fail("must be at most 50 mm");
    if (v.has("spokes")) s.vessel.spokes = static_cast<int>(v.child("spokes").integer(3, 1024));
    if (v.has("skinning")) {
      s.vessel.skinning = v.child("skinning").one_of({"rmf", "spokes"}) == std::string("rmf") ? VesselSkinning::rmf : VesselSkinning::spokes;
    }
    if (v.has("blood_filled")) s.vessel.blood_filled = v.child("blood_filled").boolean();
    if (v.has("newton_iterations")) s.vessel.newton_iterations = static_cast<int>(v.child("newton_iterations").integer(1, 100));
  } else if (top.has("vessel")) {
    top.child("vessel").fail("only for kind: vessel");
  }
  if (top.has("gravity_mm_per_s2")) s.gravity = top.child("gravity_mm_per_s2").vec3();
  if (top.has("fixed")) {
    for (const auto& item : top.child("fixed").items()) {
      s.fixed.push_back(fixed_of(item));
      if (s.model == ModelKind::vessel && s.fixed.back().kind == FixedRegionSpec::Kind::label) {
        item.child("label").fail("a centerline has no labels (kind: vessel): use box, box_fraction or half_space");
      }
      if (s.model == ModelKind::vessel && s.fixed.back().axes != 7) item.child("axes").fail("kind: vessel fixes whole atoms");
      if (s.fixed.back().axes != 7 && s.model == ModelKind::fem && s.fem_solver == FemSolver::dynamic) {
        item.child("axes").fail("fixing some axes only needs solver: static or implicit for kind: fem (the explicit "
                                "dynamics fixes whole nodes)");
      }
    }
  }
  if (top.has("tools")) {
    for (const auto& item : top.child("tools").items()) {
      s.tools.push_back(tool_of(item, ToolParseContext{s, base_dir}));
    }
  }

  const YamlField t = top.child("time");
  t.only({"duration_s", "dt_s", "safety_factor", "max_step_halvings"});
  // Bounds of a rehearsal, not of physics: at most a day of simulated time, steps of at least a
  // nanosecond (the explicit models' critical steps are microseconds to milliseconds). How long a
  // run within them takes on this machine is estimated when it starts (ctsurg-sim --force).
  s.duration_s = t.child("duration_s").positive();
  if (s.duration_s > kMaxDurationS) {
    t.child("duration_s").fail("must be at most " + YamlField::num(kMaxDurationS) + " s (a day of simulated time)");
  }
  if (t.has("dt_s")) {
    const YamlField dt = t.child("dt_s");
    if (dt.is_scalar() && dt.text() == "auto") {
      s.dt_s = 0;
    } else {
      s.dt_s = dt.positive();
      if (s.dt_s > s.duration_s) dt.fail("the step is longer than the run");
      if (s.dt_s < kMinStepS) dt.fail("must be at least " + YamlField::num(kMinStepS) + " s");
    }
  }
  if (t.has("safety_factor")) {
    s.safety_factor = t.child("safety_factor").positive();
    if (s.safety_factor > 1) t.child("safety_factor").fail("must be in (0, 1]");
  }
  if (t.has("max_step_halvings")) s.max_step_halvings = static_cast<int>(t.child("max_step_halvings").integer(0, 10));
  for (const auto& tool : s.tools) {
    if (tool.start_s >= s.duration_s) {
      throw InputError(name, tool.label + ".start_s", "the tool starts after the run ends (duration_s " +
                                                          YamlField::num(s.duration_s) + ")");
    }
  }

  const YamlField o = top.child("output");
  o.only({"trajectory", "frame_interval_s", "particles"});
  s.trajectory = resolve_scenario_path(base_dir, o.child("trajectory").text());
  s.frame_interval_s = o.has("frame_interval_s") ? o.child("frame_interval_s").positive() : s.duration_s / 50;
  if (s.frame_interval_s > s.duration_s) o.child("frame_interval_s").fail("longer than the run");
  if (s.duration_s / s.frame_interval_s > kMaxFrames) {
    o.child("frame_interval_s").fail("gives more than " + YamlField::num(kMaxFrames) + " frames over time.duration_s");
  }
  if (o.has("particles")) s.write_particles = o.child("particles").boolean();
  if (top.has("render")) {
    for (const auto& item : top.child("render").items()) {
      item.only({"name", "layout", "frames", "view", "size", "reference"});
      RenderRequest r;
      r.name = item.child("name").text();
      if (r.name.empty() || r.name.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_-") !=
                                std::string::npos) {
        item.child("name").fail("use letters, digits, '_' and '-' only (it names a file)");
      }
      for (const auto& other : s.render) {
        if (other.name == r.name) item.child("name").fail("'" + r.name + "' is used twice");
      }
      if (item.has("layout")) r.layout = item.child("layout").one_of({"single", "side-by-side", "overlay", "heat-map", "viewer"});
      if (item.has("frames")) r.frames = item.child("frames").text();
      if (r.layout == "viewer") {
        // An animated glTF and its HTML page: every frame unless told otherwise; no comparison.
        if (!item.has("frames")) r.frames = "all";
        if (item.has("reference")) item.child("reference").fail("a viewer plays one model: no reference");
      }
      if (item.has("view")) r.view = item.child("view").text();
      if (item.has("size")) r.size = static_cast<int>(item.child("size").integer(16, 8192));
      if (item.has("reference")) r.reference = item.child("reference").text();
      s.render.push_back(r);
    }
  }
  if (top.has("backend")) s.backend = top.child("backend").one_of({"cpu", "cuda", "auto"});
  if (top.has("threads")) s.threads = static_cast<int>(top.child("threads").integer(0, 1024));
  if (top.has("contact")) {
    const YamlField c = top.child("contact");
    if (s.model != ModelKind::fem || s.fem_solver != FemSolver::dynamic || s.fem_order != 1) {
      c.fail("only for kind: fem with solver: dynamic and linear elements (contact is part of the explicit dynamics)");
    }
    c.only({"self", "distance_mm", "bodies"});
    s.contact.enabled = true;
    if (c.has("self")) s.contact.self = c.child("self").boolean();
    if (c.has("distance_mm")) s.contact.distance_mm = c.child("distance_mm").positive();
    if (c.has("bodies")) {
      const YamlField b = c.child("bodies");
      b.only({"labels", "planes", "gap_mm"});
      if (b.has("gap_mm")) s.contact.gap_mm = b.child("gap_mm").non_negative();
      if (b.has("labels")) s.contact.split_labels = b.child("labels").boolean();
      if (b.has("planes")) {
        for (const auto& item : b.child("planes").items()) {
          item.only({"point_mm", "normal"});
          HalfSpace h{item.child("point_mm").vec3(), item.child("normal").vec3()};
          if (h.normal == std::array<double, 3>{0, 0, 0}) item.child("normal").fail("must not be zero");
          s.contact.split_planes.push_back(h);
        }
      }
    }
    for (const ToolAction& tool : s.tools) {
      if (tool.acts() == ToolPrimitive::remove) {
        c.fail(std::string("not with a tool that removes tissue (") + tool.label + "): the bodies are the mesh's pieces at the start");
      }
    }
  }
  if (top.has("solver")) {
    if (s.model != ModelKind::fem || s.fem_solver == FemSolver::dynamic)
      top.child("solver").fail("only for kind: fem with solver: static or implicit (the Newton solves' settings)");
    s.solver = solver_of(top.child("solver"));
    if (s.solver.local_region_mm > 0) {
      // The local region (fem/fem_local_region.h) couples quasi-static solves on linear tets around the tools.
      const YamlField r = top.child("solver").child("local_region");
      if (s.fem_solver != FemSolver::static_equilibrium) r.fail("only with solver: static (the region couples quasi-static solves)");
      if (s.fem_order != 1) r.fail("needs linear (4-node) tets (elements: linear)");
      bool acts = false;
      for (const ToolAction& a : s.tools) acts = acts || a.acts() == ToolPrimitive::hold || a.acts() == ToolPrimitive::load;
      if (!acts) r.fail("needs a grab or force tool: the region grows around the nodes the tools hold or load");
    }
  }
  // A tool's own local region radius needs the FEM local region.
  for (size_t i = 0; i < s.tools.size(); ++i) {
    if (s.tools[i].local_region_mm > 0 && !(s.solver.local_region_mm > 0)) {
      const YamlField item = top.child("tools").items()[i];
      item.child(item.has("grab") ? "grab" : item.has("clamp") ? "clamp" : "force")
          .child("local_region_mm")
          .fail("a tool's own local region radius needs solver: {local_region: {radius_mm: R}} (kind: fem, solver: static)");
    }
  }
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
