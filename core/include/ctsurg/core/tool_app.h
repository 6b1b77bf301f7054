// The common frame of every ctsurg-<step> tool: CLI11 arguments with --help and --version, spdlog
// logging (-v, -q), and the exit-code contract: 0 success, 1 runtime failure, 2 bad usage or bad
// input (InputError). A tool's main() is one call to run_tool().
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <vector>

namespace ctsurg {

struct ToolContext {
  std::string name;                       // "ctsurg-import"
  std::vector<std::string> command_line;  // argv as given
};

// Declares options on `app`, parses argv, then calls `run`. Returns the process exit code.
int run_tool(int argc, char** argv, const std::string& name, const std::string& description,
             const std::function<void(CLI::App&)>& declare, const std::function<void(const ToolContext&)>& run);

}  // namespace ctsurg
