// A point of a scenario field (a tool's keyframe, an inclusion's centre): position_mm (LPS mm),
// at_fraction (of the tissue's rest bounding box) or, where allowed, offset_mm (from the first keyframe);
// exactly one, checked, with the field's path in messages.
#pragma once

#include "ctsurg/sim/scenario/scenario.h"

#include "yaml_field.h"

namespace ctsurg::sim {

PointSpec point_of(const YamlField& f, bool offset_allowed);

}  // namespace ctsurg::sim
