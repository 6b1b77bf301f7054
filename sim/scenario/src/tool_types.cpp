#include "ctsurg/sim/scenario/tool_type.h"

#include "ctsurg/core/error.h"

namespace ctsurg::sim {

// One line per tool kind (sim/scenario/src/tools/).
extern const ToolType kGrabTool, kClampTool, kProbeTool, kCutTool, kForceTool, kInstrumentTool, kSutureTool, kCauteryTool;

const std::vector<const ToolType*>& tool_types() {
  static const std::vector<const ToolType*> types{&kGrabTool,  &kClampTool,      &kProbeTool,  &kCutTool,
                                                  &kForceTool, &kInstrumentTool, &kSutureTool, &kCauteryTool};
  return types;
}

const ToolType* find_tool_type(const std::string& name) {
  for (const ToolType* t : tool_types())
    if (name == t->name) return t;
  return nullptr;
}

std::string tool_type_names(const std::string& suffix) {
  std::string names;
  for (const ToolType* t : tool_types()) names += (names.empty() ? "" : ", ") + std::string(t->name) + suffix;
  return names;
}

std::string live_tool_names() {
  std::string names;
  for (const ToolType* t : tool_types())
    if (t->live) names += (names.empty() ? "" : ", ") + std::string(t->name);
  return names;
}

const ToolType& tool_type(const std::string& name, const std::string& where, const std::string& field) {
  const ToolType* t = find_tool_type(name);
  if (t == nullptr) throw InputError(where, field, "unknown tool '" + name + "' (the tools are " + tool_type_names() + ")");
  return *t;
}

}  // namespace ctsurg::sim
