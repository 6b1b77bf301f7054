// Tools as plug-ins. A tool kind (grab, clamp, probe, cut, force, instrument, suture, cautery) is one
// file in sim/scenario/src/tools/ holding one ToolType: the scenario key that names it, the engine
// primitive it acts through (base/simulation_engine.h: an engine never sees the tool kind), how the
// trajectory records it (and so how ctsurg-render and the live page draw it), whether the live page
// may begin one, and the function that reads and checks its own section of a scenario. The registry
// (src/tool_types.cpp) lists every type once; nothing else names a tool kind.
//
// Adding a tool (docs/architecture.md, "Adding a tool"): a file in src/tools/ with its ToolType and
// parser, one line in the registry, one in the CMake list. A tool that acts through a primitive no
// engine has yet (the cautery's remove) also adds the primitive and each engine's case for it.
#pragma once

#include "ctsurg/sim/base/simulation_engine.h"

#include <filesystem>
#include <string>
#include <vector>

namespace ctsurg::sim {

class YamlField;    // src/yaml_field.h
struct Scenario;    // scenario.h
struct ToolAction;  // scenario.h

// How the trajectory records a tool each frame (core/trajectory_file.h), and so how it is drawn.
enum class ToolRecord {
  sphere,      // its centre and radius (0 while it holds nothing), under the type's record_name
  blade,       // its edge's two ends and whether it is on
  instrument,  // its mesh once, then its pose each frame
  stitches,    // each stitch's two ends and whether it is placed
};

// What a tool's parser is given besides its list item.
struct ToolParseContext {
  const Scenario& scenario;          // what the scenario says before tools: (model, solver, elements)
  std::filesystem::path base_dir;    // a relative file (an instrument's mesh) is relative to this folder
};

struct ToolType {
  const char* name = "";             // the scenario's key: tools: [{NAME: {...}}]
  ToolPrimitive acts = ToolPrimitive::hold;
  ToolRecord record = ToolRecord::sphere;
  const char* record_name = "";      // sphere: the kind the trajectory names (a clamp records as "grab")
  bool live = false;                 // a live session may begin one from the page (sim/live)
  // Reads `item`'s section (item.child(name)) into `tool`, whose label and type are set, and checks it
  // against the model; fails (InputError naming the file and field) on anything wrong.
  void (*parse)(const YamlField& item, const ToolParseContext& context, ToolAction& tool) = nullptr;
};

// Every tool type, in the order messages list them.
const std::vector<const ToolType*>& tool_types();
// The type the scenario key `name` names, or nullptr.
const ToolType* find_tool_type(const std::string& name);
// The type named `name`; InputError(where, field, ...) listing the known names when there is none.
const ToolType& tool_type(const std::string& name, const std::string& where = "tools", const std::string& field = "tool");
// "grab, clamp, probe, cut, force, instrument, suture, cautery" (with `suffix` after each: ":").
std::string tool_type_names(const std::string& suffix = "");
// The tools a live session may begin (ToolType::live): "grab, probe, cut".
std::string live_tool_names();

}  // namespace ctsurg::sim
