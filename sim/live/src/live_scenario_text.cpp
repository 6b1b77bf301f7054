#include "live_scenario_text.h"

#include "ctsurg/core/error.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>

namespace ctsurg::sim {

namespace fs = std::filesystem;

std::string exact_number(double value) {
  char text[40];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

namespace {

YAML::Node vec3_node(const std::array<double, 3>& v) {
  YAML::Node n(YAML::NodeType::Sequence);
  for (const double c : v) n.push_back(exact_number(c));
  n.SetStyle(YAML::EmitterStyle::Flow);
  return n;
}

YAML::Node tool_node(const ToolAction& tool) {
  YAML::Node body(YAML::NodeType::Map);
  if (tool.type->record == ToolRecord::blade) {
    body["blade_edge_mm"] = vec3_node(tool.blade_edge_mm);
  } else {
    body["radius_mm"] = exact_number(tool.radius_mm);
  }
  body["start_s"] = exact_number(tool.start_s);
  if (std::isfinite(tool.end_s)) body["end_s"] = exact_number(tool.end_s);
  YAML::Node path(YAML::NodeType::Sequence);
  for (const Keyframe& k : tool.path) {
    YAML::Node key(YAML::NodeType::Map);
    key["t"] = exact_number(k.t);
    key["position_mm"] = vec3_node(k.point.value);
    key.SetStyle(YAML::EmitterStyle::Flow);
    path.push_back(key);
  }
  body["path"] = path;
  YAML::Node item(YAML::NodeType::Map);
  item[tool.kind()] = body;
  return item;
}

}  // namespace

std::string live_scenario_text(const std::string& text, const Scenario& s, const std::vector<ToolAction>& tools,
                               double duration_s, const fs::path& trajectory_file) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw InputError("live session", "scenario", std::string("its text is not YAML: ") + e.what());
  }
  if (!root.IsMap()) throw InputError("live session", "scenario", "its text is not a YAML map");
  root["name"] = s.name;
  // The files as the session read them, absolute: the saved scenario may live in another folder.
  if (root["model"] && root["model"].IsMap()) {
    YAML::Node model = root["model"];
    const auto absolute = [&](const char* key, const fs::path& p) {
      if (!p.empty() && model[key]) model[key] = fs::absolute(p).lexically_normal().string();
    };
    absolute("grid", s.grid);
    absolute("surface", s.surface);
    absolute("tetmesh", s.tetmesh);
    absolute("centerline", s.centerline);
  }
  if (root["tools"] && root["tools"].IsSequence()) {
    for (size_t i = 0; i < s.tools.size() && i < root["tools"].size(); ++i) {
      YAML::Node item = root["tools"][i];
      if (s.tools[i].type->record == ToolRecord::instrument && item["instrument"]) {
        item["instrument"]["mesh"] = fs::absolute(s.tools[i].instrument_mesh).lexically_normal().string();
      }
    }
  } else {
    root["tools"] = YAML::Node(YAML::NodeType::Sequence);
  }
  for (const ToolAction& tool : tools) root["tools"].push_back(tool_node(tool));
  if (!root["time"] || !root["time"].IsMap()) root["time"] = YAML::Node(YAML::NodeType::Map);
  root["time"]["duration_s"] = exact_number(duration_s);
  if (!root["output"] || !root["output"].IsMap()) root["output"] = YAML::Node(YAML::NodeType::Map);
  root["output"]["frame_interval_s"] = exact_number(s.frame_interval_s);
  root["output"]["trajectory"] = trajectory_file.string();
  YAML::Emitter out;
  out << root;
  return std::string("# A live session (ctsurg sim/live), saved: ctsurg-sim on this file replays it.\n") + out.c_str() + "\n";
}

}  // namespace ctsurg::sim
