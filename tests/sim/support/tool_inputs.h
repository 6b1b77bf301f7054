// A tool as an engine sees it (base/simulation_engine.h: the primitive it acts through), for the
// engines' tests: a sphere tool (hold, load, push_sphere, remove) active at `centre`, named as the
// scenario would name it ("tools[index] (name)").
#pragma once

#include "ctsurg/sim/base/simulation_engine.h"

#include <string>

namespace ctsurg::sim::test {

inline ToolInput sphere_tool_input(ToolPrimitive acts, const std::string& name, const Vec3& centre, double radius_mm,
                                   bool active = true, int index = 0) {
  ToolInput t;
  t.acts = acts;
  t.name = name;
  t.label = "tools[" + std::to_string(index) + "] (" + name + ")";
  t.radius_mm = radius_mm;
  t.active = active;
  t.centre = centre;
  t.start_centre = centre;
  return t;
}

// A cautery's tip (the remove primitive) of `radius_mm` removing at most `rate` mm^3/s.
inline ToolInput cautery_input(const Vec3& centre, double radius_mm, double rate, bool active = true) {
  ToolInput t = sphere_tool_input(ToolPrimitive::remove, "cautery", centre, radius_mm, active);
  t.removal_rate_mm3_s = rate;
  return t;
}

}  // namespace ctsurg::sim::test
