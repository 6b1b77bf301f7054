#include "ctsurg/sim/base/simulation_engine.h"

namespace ctsurg::sim {

const char* to_string(ToolPrimitive primitive) {
  switch (primitive) {
    case ToolPrimitive::hold: return "hold";
    case ToolPrimitive::load: return "load";
    case ToolPrimitive::push_sphere: return "push_sphere";
    case ToolPrimitive::push_shape: return "push_shape";
    case ToolPrimitive::separate: return "separate";
    case ToolPrimitive::stitch: return "stitch";
    case ToolPrimitive::remove: return "remove";
  }
  return "?";
}

}  // namespace ctsurg::sim
