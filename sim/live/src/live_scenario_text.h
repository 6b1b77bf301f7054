// A live session's recording as scenario text (live_session.h): the scenario's own YAML with the model's
// (and instruments') files made absolute, name, time.duration_s, output.frame_interval_s and
// output.trajectory written out, and the user's tools appended to `tools:` as keyframed paths of LPS
// positions. Every number written is %.17g, so it parses back to the same double.
#pragma once

#include "ctsurg/sim/scenario/scenario.h"

#include <filesystem>
#include <string>
#include <vector>

namespace ctsurg::sim {

// text: the YAML (or JSON) `scenario` was parsed from; tools: the user's (grab, probe or cut, position_mm
// keyframes); duration_s: the run's (s). InputError("live session", ...) when text is not a YAML map.
std::string live_scenario_text(const std::string& text, const Scenario& scenario, const std::vector<ToolAction>& tools,
                               double duration_s, const std::filesystem::path& trajectory_file);

// %.17g: the shortest text that always parses back to the same double.
std::string exact_number(double value);

}  // namespace ctsurg::sim
