// The scenario file's sections, each parsed and checked by its own file (sections/<name>_section.cpp;
// the material section by scenario_material.cpp, each tool's by its plug-in in tools/). scenario.cpp
// calls them in this order, which is the order of their dependencies: a section reads what the ones
// before it set in the Scenario (the model's kind and solver, the tools). Every check names the file
// and the field (yaml_field.h).
#pragma once

#include "ctsurg/sim/scenario/scenario.h"
#include "yaml_field.h"

#include <filesystem>

namespace ctsurg::sim {

// top: the document's top level; base_dir: the folder the scenario's relative paths start from.
void parse_model_section(const YamlField& top, const std::filesystem::path& base_dir, Scenario& s);  // model
void parse_vessel_section(const YamlField& top, Scenario& s);                                        // vessel (kind: vessel)
void parse_fixed_section(const YamlField& top, Scenario& s);                                         // fixed
void parse_tools_section(const YamlField& top, const std::filesystem::path& base_dir, Scenario& s);  // tools
void parse_time_section(const YamlField& top, Scenario& s);                                          // time
void parse_output_section(const YamlField& top, const std::filesystem::path& base_dir, Scenario& s); // output
void parse_render_section(const YamlField& top, Scenario& s);                                        // render
void parse_contact_section(const YamlField& top, Scenario& s);                                       // contact
void parse_solver_section(const YamlField& top, Scenario& s);                                        // solver

}  // namespace ctsurg::sim
