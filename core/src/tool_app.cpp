#include "ctsurg/core/tool_app.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/memory_guard.h"
#include "ctsurg/core/progress_bar.h"
#include "ctsurg/core/version.h"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <csignal>
#include <exception>
#include <iostream>
#include <new>

namespace ctsurg {

int run_tool(int argc, char** argv, const std::string& name, const std::string& description,
             const std::function<void(CLI::App&)>& declare, const std::function<void(const ToolContext&)>& run) {
  CLI::App app(description, name);
  app.set_version_flag("--version", std::string(name) + " (ctsurg) " + kVersion);
  bool verbose = false, quiet = false;
  app.add_flag("-v,--verbose", verbose, "More log output (debug level)");
  app.add_flag("-q,--quiet", quiet, "Only errors; no progress bar");
  declare(app);

  auto logger = spdlog::stderr_color_st(name);
  logger->set_pattern("%n: %^%l%$: %v");
  spdlog::set_default_logger(logger);

  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << name << ": error: " << e.what() << "\nRun '" << name << " --help' for usage.\n";
    return 2;
  }
  spdlog::set_level(quiet ? spdlog::level::err : verbose ? spdlog::level::debug : spdlog::level::info);
  ProgressBar::set_globally_enabled(!quiet);

  // A file-size limit (ulimit -f) would kill the process with SIGXFSZ, leaving its temporary
  // files behind; ignored, the write fails with EFBIG and the writer reports it (checked_write.h).
  std::signal(SIGXFSZ, SIG_IGN);

  ToolContext ctx{name, std::vector<std::string>(argv, argv + argc)};
  try {
    apply_memory_cap();
    run(ctx);
    return 0;
  } catch (const InputError& e) {
    spdlog::error("{}", e.what());
    return 2;
  } catch (const std::bad_alloc&) {
    const std::string cap = memory_cap_note();
    spdlog::error("out of memory{}", cap.empty() ? std::string() : " (" + cap + ")");
    return 1;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
}

}  // namespace ctsurg
