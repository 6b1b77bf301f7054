// Tests for ctsurg/sim/scenario/scenario_model.h: which files each kind of model reads and its label,
// and that ctsurg-sim --describe (describe_scenario) lists exactly those files.
#include "ctsurg/sim/scenario/scenario_model.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace ctsurg::sim {
namespace {

Scenario scenario(const std::string& model, const std::string& law = "") {
  return parse_scenario("ctsurg_scenario: 1\nmodel: " + model + "\nmaterial: {preset: kidney" + (law.empty() ? "" : ", law: " + law) + "}\nfixed: [{box_fraction: {min: [0, 0, 0], max: [1, 1, 0.1]}}]\n"
                            "time: {duration_s: 0.1}\noutput: {trajectory: out.h5}\n",
                        "s.yaml", "/data");
}

TEST(ScenarioModel, FilesReadAndLabelPerKindOfModel) {
  struct Case {
    std::string model;
    bool grid, tetmesh, surface;
    std::string label;
    std::string law = "";  // material.law (kind: fem)
  };
  const std::vector<Case> cases{
      {"{kind: spring_grid, grid: g.h5, surface: s.h5}", true, false, true, "spring_grid"},
      {"{kind: explicit_springs, grid: g.h5}", true, false, false, "explicit_springs (grid)"},
      {"{kind: explicit_springs, springs_from: tetmesh, grid: g.h5, tetmesh: t.h5}", true, true, false, "explicit_springs (tetmesh)"},
      {"{kind: fem, tetmesh: t.h5, surface: s.h5}", false, true, true, "fem stvk (dynamic)", "stvk"},
      {"{kind: fem, grid: g.h5, tetmesh: t.h5, solver: static}", false, true, false, "fem neo_hookean (static)"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.model);
    const Scenario s = scenario(c.model, c.law);
    const ModelInputs in = model_inputs(s);
    EXPECT_EQ(in.grid, c.grid);
    EXPECT_EQ(in.tetmesh, c.tetmesh);
    EXPECT_EQ(in.surface, c.surface);
    EXPECT_EQ(model_label(s), c.label);
    // --describe lists what the run reads, no more.
    const auto inputs = nlohmann::json::parse(describe_scenario(s))["inputs"];
    EXPECT_EQ(inputs.contains("grid"), c.grid);
    EXPECT_EQ(inputs.contains("tetmesh"), c.tetmesh);
    EXPECT_EQ(inputs.contains("surface"), c.surface);
    if (c.grid) {
      EXPECT_EQ(inputs["grid"], "/data/g.h5");
    }
  }
}

}  // namespace
}  // namespace ctsurg::sim
