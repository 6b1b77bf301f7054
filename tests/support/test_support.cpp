#include "test_support.h"

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <atomic>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>
#include <unistd.h>

namespace fs = std::filesystem;

namespace ctsurg::test {

TempDir::TempDir() {
  static std::atomic<int> counter{0};
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = info ? std::string(info->test_suite_name()) + "." + info->name() : "ctsurg";
  for (auto& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.') c = '_';
  path_ = fs::temp_directory_path() /
          ("ctsurg-test-" + name + "-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
  fs::remove_all(path_);
  fs::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

static std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

CommandResult run_shell(const std::string& command_line) {
  CommandResult r;
  FILE* pipe = ::popen((command_line + " 2>&1").c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf{};
  while (std::fgets(buf.data(), buf.size(), pipe)) r.output += buf.data();
  const int status = ::pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return r;
}

CommandResult run_tool(const std::string& tool, const std::vector<std::string>& args) {
  std::string cmd = quote(std::string(CTSURG_TOOL_DIR) + "/" + tool);
  for (const auto& a : args) cmd += " " + quote(a);
  return run_shell("CTSURG_NO_PROGRESS=1 " + cmd + " </dev/null");
}

fs::path shared_data_dir() {
  const fs::path p = CTSURG_SHARED_DATA_DIR;
  return fs::is_directory(p) ? fs::canonical(p) : fs::path();
}

std::vector<fs::path> files_in(const fs::path& folder) {
  std::vector<fs::path> out;
  for (const auto& e : fs::recursive_directory_iterator(folder)) {
    if (e.is_regular_file()) out.push_back(e.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

fs::path source_dir() { return CTSURG_SOURCE_DIR; }

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

Provenance test_provenance() { return {"test", "0", {}, {}, nlohmann::json::array()}; }

std::string python_with_vtk() {
  for (const std::string candidate : {"/usr/bin/python3", "python3"})
    if (run_shell(candidate + " -c 'import vtk' 2>/dev/null").exit_code == 0) return candidate;
  return "";
}

}  // namespace ctsurg::test
