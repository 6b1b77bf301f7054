// The HTML viewer's page template and script, embedded at build time (render/viewer/embed_viewer.cmake
// writes their definitions into the build folder when the build has the viewer: CTSURG_HTML_VIEWER).
#pragma once

#include <cstddef>

namespace ctsurg::html_viewer_assets {

extern const char kLibrary[];          // the viewer library's npm name and version, e.g. "@google/model-viewer 4.4.0"
extern const unsigned char kPage[];    // render/viewer/viewer_page.html, UTF-8
extern const std::size_t kPageSize;
extern const unsigned char kScript[];  // the library's ES module bundle, UTF-8
extern const std::size_t kScriptSize;

}  // namespace ctsurg::html_viewer_assets
