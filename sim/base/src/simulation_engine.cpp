#include "ctsurg/sim/base/simulation_engine.h"

namespace ctsurg::sim {

const char* to_string(ToolKind kind) {
  switch (kind) {
    case ToolKind::grab: return "grab";
    case ToolKind::probe: return "probe";
    case ToolKind::cut: return "cut";
    case ToolKind::force: return "force";
    case ToolKind::instrument: return "instrument";
    case ToolKind::suture: return "suture";
  }
  return "?";
}

}  // namespace ctsurg::sim
