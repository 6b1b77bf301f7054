// The scenario's `tools:` section: a list of tools, each exactly one key of the registry
// (tool_type.h), whose type reads its own section.
#include "scenario_sections.h"

#include "ctsurg/core/error.h"

namespace ctsurg::sim {
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

}  // namespace

void parse_tools_section(const YamlField& top, const std::filesystem::path& base_dir, Scenario& s) {
  if (top.has("tools")) {
    for (const auto& item : top.child("tools").items()) {
      s.tools.push_back(tool_of(item, ToolParseContext{s, base_dir}));
    }
  }
}

}  // namespace ctsurg::sim
