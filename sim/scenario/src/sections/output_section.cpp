// The scenario's `output:` section: the trajectory file, the frame interval and whether particles are
// written. Needs the time section.
#include "scenario_sections.h"

#include "ctsurg/core/error.h"

namespace ctsurg::sim {

void parse_output_section(const YamlField& top, const std::filesystem::path& base_dir, Scenario& s) {
  const YamlField o = top.child("output");
  o.only({"trajectory", "frame_interval_s", "particles"});
  s.trajectory = resolve_scenario_path(base_dir, o.child("trajectory").text());
  s.frame_interval_s = o.has("frame_interval_s") ? o.child("frame_interval_s").positive() : s.duration_s / 50;
  if (s.frame_interval_s > s.duration_s) o.child("frame_interval_s").fail("longer than the run");
  if (s.duration_s / s.frame_interval_s > kMaxFrames) {
    o.child("frame_interval_s").fail("gives more than " + YamlField::num(kMaxFrames) + " frames over time.duration_s");
  }
  if (o.has("particles")) s.write_particles = o.child("particles").boolean();
}

}  // namespace ctsurg::sim
