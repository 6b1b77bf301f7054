// What the moving tools' sections share (tools/*.cpp): the keyframed path, the window and
// snap_to_tissue.
#pragma once

#include "ctsurg/sim/scenario/scenario.h"
#include "yaml_field.h"

#include <initializer_list>
#include <string>
#include <vector>

namespace ctsurg::sim {

// A moving tool's own fields followed by the shared ones (start_s, end_s, path, snap_to_tissue), for
// YamlField::only.
std::vector<std::string> path_tool_fields(std::initializer_list<const char*> own);

// Reads f's path (>= 1 keyframe, increasing t; each t, position_mm / at_fraction / offset_mm and, with
// `rotations`, a quaternion or rotation), then start_s (default: the first keyframe's t), end_s
// (default: +inf, after start_s) and snap_to_tissue. A non-zero rotation fails with `rotation_refusal`
// when that is not empty.
void read_tool_path(const YamlField& f, ToolAction& t, bool rotations, const std::string& rotation_refusal = "");

// The grip fields: grip (nodes | volume), grip_edge_mm and, for the hold tools (grab, clamp: `penalty`),
// grip_stiffness_ratio. A hold's volume grip is a penalty: it needs kind: fem with solver
// static_equilibrium or implicit; a force's (not `penalty`) spreads a load: kind: fem, any solver (fails
// on the field otherwise).
inline constexpr const char* kGripFields[] = {"grip", "grip_stiffness_ratio", "grip_edge_mm"};
void read_grip(const YamlField& f, const Scenario& s, ToolAction& t, bool penalty = true);

// A tool that pushes the tissue (probe, instrument) on kind: fem needs the explicit dynamics (contact is
// part of no other solver): fails on `item` naming the tool otherwise.
void require_fem_contact_solver(const YamlField& item, const Scenario& s, const char* tool);

}  // namespace ctsurg::sim
