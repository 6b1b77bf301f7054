// The scenario's `render:` section: the pictures the pipeline makes of the run with ctsurg-render
// (scripts/render_plan.py turns each request into its command line).
#include "scenario_sections.h"

#include "ctsurg/core/error.h"

namespace ctsurg::sim {

void parse_render_section(const YamlField& top, Scenario& s) {
  if (top.has("render")) {
    for (const auto& item : top.child("render").items()) {
      item.only({"name", "layout", "frames", "view", "size", "reference"});
      RenderRequest r;
      r.name = item.child("name").text();
      if (r.name.empty() || r.name.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_-") !=
                                std::string::npos) {
        item.child("name").fail("use letters, digits, '_' and '-' only (it names a file)");
      }
      for (const auto& other : s.render) {
        if (other.name == r.name) item.child("name").fail("'" + r.name + "' is used twice");
      }
      if (item.has("layout")) r.layout = item.child("layout").one_of({"single", "side-by-side", "overlay", "heat-map", "viewer"});
      if (item.has("frames")) r.frames = item.child("frames").text();
      if (r.layout == "viewer") {
        // An animated glTF and its HTML page: every frame unless told otherwise; no comparison.
        if (!item.has("frames")) r.frames = "all";
        if (item.has("reference")) item.child("reference").fail("a viewer plays one model: no reference");
      }
      if (item.has("view")) r.view = item.child("view").text();
      if (item.has("size")) r.size = static_cast<int>(item.child("size").integer(16, 8192));
      if (item.has("reference")) r.reference = item.child("reference").text();
      s.render.push_back(r);
    }
  }
}

}  // namespace ctsurg::sim
