// The live page's files (sim/live/page: the page, its script and npm three.js), embedded at build time
// by sim/live/page/embed_live_page.cmake into live_page_assets.cpp (generated in the build folder), so
// ctsurg-live serves them from memory: no files and no network at run time.
#pragma once

#include <cstddef>
#include <span>
#include <string_view>

namespace ctsurg::sim::live_page {

struct Asset {
  std::string_view name;          // the path under the session's URL: "" (the page), "live_page.js", ...
  std::string_view content_type;  // e.g. "text/html; charset=utf-8", "text/javascript; charset=utf-8"
  std::span<const unsigned char> bytes;
};

// Every embedded file, the page ("") first.
std::span<const Asset> assets();
// The WebGL library and its version, e.g. "three 0.187.0" (its package.json).
std::string_view library();

}  // namespace ctsurg::sim::live_page
