#include "point_field.h"

#include <string>

namespace ctsurg::sim {

PointSpec point_of(const YamlField& f, bool offset_allowed) {
  int given = 0;
  PointSpec p;
  if (f.has("position_mm")) {
    p = {PointSpec::Kind::position_mm, f.child("position_mm").vec3()};
    ++given;
  }
  if (f.has("at_fraction")) {
    p = {PointSpec::Kind::at_fraction, f.child("at_fraction").vec3()};
    ++given;
  }
  if (f.has("offset_mm")) {
    if (!offset_allowed) f.child("offset_mm").fail("the first keyframe needs position_mm or at_fraction");
    p = {PointSpec::Kind::offset_mm, f.child("offset_mm").vec3()};
    ++given;
  }
  if (given != 1) f.fail("give exactly one of position_mm, at_fraction" + std::string(offset_allowed ? ", offset_mm" : ""));
  return p;
}

}  // namespace ctsurg::sim
