// Helpers shared by the test programs: temporary folders, running tools, the shared data folder.
#pragma once

#include "ctsurg/core/provenance.h"

#include <filesystem>
#include <string>
#include <vector>

namespace ctsurg::test {

// A fresh, empty folder removed when the object dies.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

// Runs a ctsurg tool from the build's bin folder, e.g. run_tool("ctsurg-import", {"a", "b"}).
CommandResult run_tool(const std::string& tool, const std::vector<std::string>& args);
// Runs any shell command line.
CommandResult run_shell(const std::string& command_line);
// A Python that imports vtk (python3-vtk9 installs for the system Python; a python3 earlier on PATH,
// pyenv or a venv, may lack it): "/usr/bin/python3" or "python3", or "" when neither has it.
std::string python_with_vtk();

// ../shared/data (real scans), or an empty path when it is not there.
std::filesystem::path shared_data_dir();
// Skips the current test (GTEST_SKIP) when the shared data is absent.
#define CTSURG_REQUIRE_SHARED_DATA()                                                       \
  do {                                                                                     \
    if (::ctsurg::test::shared_data_dir().empty()) GTEST_SKIP() << "../shared/data absent"; \
  } while (0)

// Files in a folder (recursively) whose names start with `prefix`; used to prove no partial output.
std::vector<std::filesystem::path> files_in(const std::filesystem::path& folder);

std::filesystem::path source_dir();

// The whole content of a file ("" when it cannot be read), to compare outputs byte for byte.
std::string read_bytes(const std::filesystem::path& path);
// Provenance for files that tests write themselves.
Provenance test_provenance();

}  // namespace ctsurg::test
