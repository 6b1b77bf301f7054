// Screenshots of pages in a real headless Chromium (Debian's `chromium`, installed by
// scripts/install-deps.sh) through tests/support/chromium/chromium_screenshot.mjs (node; the DevTools
// protocol on a pipe), for tests of what ctsurg writes for browsers: the pictures, the requests each
// page made (to prove nothing went to the network), its reports, console lines and exceptions.
#pragma once

#include "test_support.h"

#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace ctsurg::test {

// Whether Chromium is installed (CTSURG_CHROMIUM, or `chromium` on the PATH).
inline bool chromium_installed() {
  const char* named = std::getenv("CTSURG_CHROMIUM");
  return run_shell(std::string("command -v ") + (named && *named ? named : "chromium") + " >/dev/null").exit_code == 0;
}
// Skips the current test when Chromium is absent (CI installs it: scripts/install-deps.sh).
#define CTSURG_REQUIRE_CHROMIUM()                                                                                      \
  do {                                                                                                                 \
    if (!::ctsurg::test::chromium_installed())                                                                         \
      GTEST_SKIP() << "chromium is not installed (Debian package chromium, scripts/install-deps.sh): no browser test"; \
  } while (0)

struct ChromiumRun {
  CommandResult result;                                // exit code 0 when every shot was taken; all output
  std::vector<std::string> requests, reports, console, exceptions;  // one entry per line of each kind
};

// Loads each (url, png) in turn (afresh, so URLs differing only in their #fragment too) in a viewport
// of width x height CSS pixels, waits until the JavaScript expression `wait` is truthy (at most
// timeout_ms per page), saves the screenshot to png and records JSON.stringify(`report`).
inline ChromiumRun chromium_screenshots(const std::vector<std::pair<std::string, std::filesystem::path>>& shots,
                                        const std::string& wait, const std::string& report, int width = 640,
                                        int height = 480, int timeout_ms = 60000) {
  const auto quote = [](const std::string& s) {
    std::string q = "'";
    for (const char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
  };
  std::string command = "node " + quote((source_dir() / "tests" / "support" / "chromium" / "chromium_screenshot.mjs").string()) +
                        " --size " + std::to_string(width) + "x" + std::to_string(height) + " --timeout-ms " +
                        std::to_string(timeout_ms) + " --wait " + quote(wait) + " --report " + quote(report);
  for (const auto& [url, png] : shots) command += " " + quote(url + "=" + png.string());
  ChromiumRun run;
  run.result = run_shell(command);
  std::istringstream lines(run.result.output);
  for (std::string line; std::getline(lines, line);) {
    const auto take = [&](const std::string& prefix, std::vector<std::string>& into) {
      if (line.rfind(prefix, 0) == 0) into.push_back(line.substr(prefix.size()));
    };
    take("request: ", run.requests);
    take("report: ", run.reports);
    take("console: ", run.console);
    take("exception: ", run.exceptions);
  }
  return run;
}

// A file URL for a local path (percent-encoding what a path may hold that a URL may not).
inline std::string file_url(const std::filesystem::path& path) {
  static const char* hex = "0123456789ABCDEF";
  std::string url = "file://";
  for (const unsigned char c : std::filesystem::absolute(path).string()) {
    if (std::isalnum(c) || c == '/' || c == '-' || c == '.' || c == '_' || c == '~') {
      url += static_cast<char>(c);
    } else {
      url += '%';
      url += hex[c >> 4];
      url += hex[c & 15];
    }
  }
  return url;
}

}  // namespace ctsurg::test
