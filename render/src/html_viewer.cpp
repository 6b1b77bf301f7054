#include "ctsurg/render/html_viewer.h"

#include <spdlog/fmt/fmt.h>

#include <algorithm>
#include <cctype>

#include "ctsurg/core/checked_write.h"
#include "ctsurg/core/error.h"
#include "ctsurg/core/version.h"

#if CTSURG_HTML_VIEWER
#include "html_viewer_assets.h"
#endif

namespace ctsurg {

#if CTSURG_HTML_VIEWER
namespace {

// RFC 4648 base64, with padding, on one line.
std::string base64(std::string_view bytes) {
  static constexpr char kDigits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const uint32_t v = uint32_t(uint8_t(bytes[i])) << 16 | uint32_t(uint8_t(bytes[i + 1])) << 8 | uint8_t(bytes[i + 2]);
    out += {kDigits[v >> 18], kDigits[v >> 12 & 63], kDigits[v >> 6 & 63], kDigits[v & 63]};
  }
  if (i + 1 == bytes.size()) {
    const uint32_t v = uint32_t(uint8_t(bytes[i])) << 16;
    out += {kDigits[v >> 18], kDigits[v >> 12 & 63], '=', '='};
  } else if (i + 2 == bytes.size()) {
    const uint32_t v = uint32_t(uint8_t(bytes[i])) << 16 | uint32_t(uint8_t(bytes[i + 1])) << 8;
    out += {kDigits[v >> 18], kDigits[v >> 12 & 63], kDigits[v >> 6 & 63], '='};
  }
  return out;
}

// Text for HTML element content and attribute values.
std::string html_escape(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += c;
    }
  }
  return out;
}

}  // namespace
#endif

bool html_viewer_available() { return CTSURG_HTML_VIEWER != 0; }

std::string html_viewer_library() {
#if CTSURG_HTML_VIEWER
  return html_viewer_assets::kLibrary;
#else
  return "";
#endif
}

void check_html_viewer_output(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext != ".html" && ext != ".htm") throw InputError(path.string(), "suffix", "the viewer is an HTML page: use .html");
  if (!html_viewer_available()) {
    throw InputError("--viewer", "",
                     "this ctsurg-render was built without the HTML viewer (CMake -DCTSURG_HTML_VIEWER=OFF): run "
                     "scripts/install-deps.sh (npm ci in render/viewer) and build it with the viewer");
  }
}

std::string html_viewer_page(std::string_view glb, const HtmlViewerOptions& options) {
#if CTSURG_HTML_VIEWER
  if (glb.size() < 12 || glb.substr(0, 4) != "glTF") throw RuntimeError("html_viewer_page: the model is not a binary glTF");
  const std::string_view page(reinterpret_cast<const char*>(html_viewer_assets::kPage), html_viewer_assets::kPageSize);
  const std::string_view script(reinterpret_cast<const char*>(html_viewer_assets::kScript), html_viewer_assets::kScriptSize);
  const std::string title = html_escape(options.title.empty() ? std::string("ctsurg model") : options.title);
  // The template's fields, each @CTSURG_NAME@, filled in one pass over the template (never inside
  // what is inserted: the script or the model could contain anything).
  std::string out;
  out.reserve(page.size() + script.size() + glb.size() / 3 * 4 + 64);
  std::size_t at = 0;
  while (true) {
    const std::size_t open = page.find("@CTSURG_", at);
    if (open == std::string_view::npos) break;
    const std::size_t close = page.find('@', open + 1);
    if (close == std::string_view::npos) throw RuntimeError("html_viewer_page: an unterminated field in the page template");
    const std::string_view field = page.substr(open + 8, close - open - 8);
    out.append(page.substr(at, open - at));
    if (field == "TITLE") out += title;
    else if (field == "GENERATOR") out += std::string("ctsurg-render ") + kVersion;
    else if (field == "LIBRARY") out += html_viewer_assets::kLibrary;
    else if (field == "VIEWER_SCRIPT") out.append(script);
    else if (field == "MODEL") out += base64(glb);
    else if (field == "TIME_OFFSET") out += fmt::format("{}", options.time_offset_s);
    else if (field == "TIME_SCALE") out += fmt::format("{}", options.time_scale);
    else if (field == "TIME_END") out += fmt::format("{}", std::max(options.time_end_s, options.time_offset_s));
    else throw RuntimeError("html_viewer_page: the page template has an unknown field @CTSURG_" + std::string(field) + "@");
    at = close + 1;
  }
  out.append(page.substr(at));
  return out;
#else
  (void)glb;
  (void)options;
  throw InputError("--viewer", "", "this ctsurg-render was built without the HTML viewer (CMake -DCTSURG_HTML_VIEWER=OFF)");
#endif
}

std::size_t add_html_viewer(OutputUnit& unit, const std::filesystem::path& path, std::string_view glb,
                            const HtmlViewerOptions& options) {
  const std::string page = html_viewer_page(glb, options);
  AtomicOutput& out = unit.add(path);
  write_file_checked(out.temp_path(), page, path.string());
  return page.size();
}

}  // namespace ctsurg
