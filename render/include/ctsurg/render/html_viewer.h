// A self-contained HTML page that shows a binary glTF (an animated trajectory from gltf_animation.h, or a
// still surface) in any browser with WebGL 2, offline: the model embedded as base64, the viewer's script
// inline, nothing fetched (the page's Content-Security-Policy forbids any network access). The viewer is
// Google's <model-viewer> (npm @google/model-viewer, with three.js and lit bundled), pinned in
// render/viewer/package-lock.json, installed by scripts/install-deps.sh and embedded into ctsurg-render
// at build time (render/viewer/embed_viewer.cmake), so the tool needs no files at run time.
//
// The page: orbit controls (drag, zoom, pan), the animation playing in a loop with play/pause, a time
// slider and the simulated time; address parameters #t=SECONDS (open paused at that simulated time) and
// orbit=AZ,EL (degrees, the views of ctsurg-render: 0,0 anterior, 90,0 the patient's left); and
// window.ctsurgViewer = {ready, error, duration} for scripts and tests. The page is about the model's
// size times 4/3 (base64) plus ~1.1 MB of script. Template: render/viewer/viewer_page.html.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>

#include "ctsurg/core/atomic_output.h"

namespace ctsurg {

struct HtmlViewerOptions {
  std::string title;          // the page's title and caption (plain text; escaped here)
  double time_offset_s = 0;   // the simulated time of the animation's first key
  double time_scale = 1.0;    // playback seconds per simulated second (as the glTF was written with)
  double time_end_s = 0;      // the simulated time of the last frame (the clock stops there while the glTF
                              //   holds the last frame); ignored when not after time_offset_s
};

// Whether this build embeds the viewer (CMake option CTSURG_HTML_VIEWER, on by default).
bool html_viewer_available();
// The embedded viewer library, e.g. "@google/model-viewer 4.4.0" ("" when not available).
std::string html_viewer_library();

// InputError(path, "suffix", ...) unless .html or .htm (any case); InputError("--viewer", ...) when
// this build has no viewer. For tools to call before any work.
void check_html_viewer_output(const std::filesystem::path& path);

// The page showing `glb` (the bytes of a .glb file).
std::string html_viewer_page(std::string_view glb, const HtmlViewerOptions& options);

// Writes the page to `path`'s temporary name in `unit` (every error checked); the caller commits.
// Returns the page's size in bytes.
std::size_t add_html_viewer(OutputUnit& unit, const std::filesystem::path& path, std::string_view glb, const HtmlViewerOptions& options);

}  // namespace ctsurg
