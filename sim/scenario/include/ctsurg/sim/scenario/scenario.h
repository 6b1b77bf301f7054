// A scenario: what a ctsurg-sim run simulates and writes. Read from a YAML file (JSON works too: it
// is YAML's flow style); data_samples/scenarios/ holds commented examples and docs/sim.md the full
// reference. Every field is checked where it enters: an unknown key, a missing one, a wrong type or a
// value out of range is an InputError naming the scenario file and the field's path
// ("tools[1].path[0].t"). Input and output paths are relative to the scenario file's folder.
//
// Units: mm (LPS), s, g; Young's modulus Pa, density g/cm^3 in the file (g/mm^3 inside).
#pragma once

#include "ctsurg/sim/base/fixed_regions.h"
#include "ctsurg/sim/base/material_presets.h"
#include "ctsurg/sim/base/rigid_pose.h"
#include "ctsurg/sim/base/simulation_engine.h"
#include "ctsurg/sim/fem/fem_engine.h"
#include "ctsurg/sim/fem/fem_material.h"
#include "ctsurg/sim/scenario/tool_type.h"
#include "ctsurg/sim/fem/fem_static_solver.h"
#include "ctsurg/sim/surface/surface_coupling.h"
#include "ctsurg/sim/vessel/vessel_skinning.h"

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace ctsurg::sim {

enum class ModelKind { spring_grid, explicit_springs, fem, vessel };
enum class SpringSource { grid, tetmesh };  // where explicit springs come from
// fem: the material law is a FemLaw (fem/laws/fem_law.h), the solver a FemSolver
// (fem/fem_engine.h).

// A point given in one of three ways; resolved to the run's frame when it starts (tool_timeline.h).
struct PointSpec {
  enum class Kind { position_mm, at_fraction, offset_mm };
  Kind kind = Kind::position_mm;
  // position_mm: LPS mm; at_fraction: (0..1)^3 of the tissue's rest bounding box (0 = its L, P, S
  // minimum corner... 1 = maximum); offset_mm: mm from the tool's first keyframe.
  std::array<double, 3> value{0, 0, 0};
};

struct Keyframe {
  double t = 0;  // s
  PointSpec point;
  // instrument: its orientation at t (the instrument's frame -> LPS, a unit quaternion {w, x, y, z});
  // absent: the previous keyframe's (the first: the identity). Slerp between keyframes.
  std::optional<Quaternion> rotation;
};

// suture: one stitch, its two points (LPS mm) and the field that gave it (for messages).
struct StitchSpec {
  std::array<double, 3> a{0, 0, 0}, b{0, 0, 0};
  std::string field;  // e.g. "tools[1].suture.stitches[0]"
};

// suture: `count` stitches spaced along the line from -> to (LPS mm), stitch k at fraction (k + 1/2) /
// count, each joining the points width_mm / 2 either side of the line along `across` (LPS; absent: the
// line's direction x the tissue's outward direction there, tool_timeline.h).
struct SutureLine {
  std::array<double, 3> from{0, 0, 0}, to{0, 0, 0};
  int count = 1;
  double width_mm = 0;
  std::optional<std::array<double, 3>> across;
  std::string field;  // "tools[1].suture.along"
};

struct ToolAction {
  const ToolType* type = nullptr;    // what kind of tool (tool_type.h: its primitive, record, parser); set by the parser
  std::string label;                 // "tools[0] (grab)", for messages
  double start_s = 0;                // active from start_s ...
  double end_s = 0;                  // ... to end_s (grab: release), s; +inf = to the end of the run
  double radius_mm = 0;              // grab, probe, force: sphere radius, mm (> 0)
  std::vector<Keyframe> path;        // >= 1 keyframe, increasing t; the tool moves linearly between them
  bool snap_to_tissue = false;       // shift the whole path so its first point is on the nearest particle
  std::array<double, 3> blade_edge_mm{0, 0, 0};  // cut: the blade's edge, centred on the path (mm, != 0)
  // force: a total force (N, LPS) shared equally by the particles or nodes inside the sphere at
  // start_s (a point load: the FEM paper's experiment), applied until end_s.
  std::array<double, 3> force_n{0, 0, 0};
  // instrument: a closed triangle mesh (.stl, .obj, .ply; mm, its own frame: the path moves its origin)
  // that pushes the tissue out of itself (base/instrument.h), and its distance grid's spacing (0: auto).
  std::filesystem::path instrument_mesh;
  double instrument_spacing_mm = 0;
  // suture: stitches placed at start_s, tightened to stitch_target_mm (mm, >= 0) by end_s and kept to the
  // end of the run; stiffness stitch_stiffness_ratio x the model's stiffest spring (springs/suture.h).
  std::vector<StitchSpec> stitches;
  std::optional<SutureLine> along;
  double stitch_target_mm = 0;
  double stitch_stiffness_ratio = 1;
  // grab, clamp, force with solver.local_region: this tool's region radius (mm, > 0); 0: the solver's.
  double local_region_mm = 0;
  // grab, clamp: grip nodes (the free nodes inside, held) | volume (the material inside, by a penalty
  // integrated over the elements: kind fem, solver static_equilibrium or implicit; fem/fem_grip.h), its
  // stiffness ratio (x E / radius^2, > 0) and edge band (mm, (0, radius]; 0: radius / 4). force: grip
  // nodes (its force shared by the free nodes inside) | volume (spread over the material inside by
  // volume: kind fem, any solver; fem/fem_tools.h) and the same edge band.
  HoldGrip grip = HoldGrip::nodes;
  double grip_stiffness_ratio = 1000;
  double grip_edge_mm = 0;
  // cautery: the most tissue it removes per second (mm^3/s, > 0).
  double removal_rate_mm3_s = 0;

  ToolPrimitive acts() const { return type->acts; }
  const char* kind() const { return type->name; }
};

// A picture the pipeline makes from the trajectory with ctsurg-render (scripts/Makefile); ctsurg-sim
// only checks and lists them (ctsurg-sim --describe).
struct RenderRequest {
  std::string name;                 // the picture's file stem, e.g. "grab_heat" -> grab_heat.png ([A-Za-z0-9_-]+)
  std::string layout = "single";    // single | side-by-side | overlay | heat-map | viewer (NAME.glb + NAME.html:
                                    // ctsurg-render --gltf --viewer, the frames animated; no reference)
  std::string frames = "last";      // ctsurg-render --frames: rest, last, all, N, A:B, A:B:STEP (viewer: default all)
  std::string view = "anterior";    // anterior, posterior, left, right, superior, inferior, or "AZ,EL"
  int size = 768;                   // pixels (square)
  std::string reference;            // comparisons: empty = the rest surface, or another scenario's name
};

struct FixedRegionSpec {
  enum class Kind { box, box_fraction, half_space, label };
  Kind kind = Kind::box;
  Box box;              // box: LPS mm; box_fraction: fractions of the rest bounding box
  HalfSpace half_space;
  uint16_t label = 0;
  uint8_t axes = 7;     // the components held: bit 0 x, 1 y, 2 z (rollers, symmetry planes); 7 = all
};

// The Newton solves of the FEM's static and implicit solvers (fem/fem_static_solver.h), from the
// scenario's `solver:` section.
struct SolverSpec {
  FemLinearSolve linear = FemLinearSolve::automatic;  // auto | direct | iterative
  double tolerance_mm = 0;         // the stopping rule in mm; 0 = the solvers' relative default
  int max_newton_iterations = 25;  // per solve or step
  // nonlinear: newton | quasi_newton (L-BFGS on the rest stiffness's factor, fem_static_solver.h)
  FemNonlinearSolve nonlinear = FemNonlinearSolve::newton;
  int max_cg_iterations = 0;       // iterative: 0 = twice the unknowns
  // local_region: {radius_mm: R}: Newton only within R mm (geodesic) of the tools' nodes, the rest from
  // the linear model factorised once (fem/fem_local_region.h); solver static, a grab or force tool.
  double local_region_mm = 0;      // 0: none (the whole mesh by the material law)
  int local_region_balance = 0;    // local_region.balance_iterations: 0 = Dirichlet coupling alone
};

// Contact between bodies and self-contact of an FEM model (fem/fem_contact.h), from the scenario's
// `contact:` section (kind: fem, solver: dynamic).
struct ContactSpec {
  bool enabled = false;
  bool self = true;                  // within one body too (folds, the lips of a cut)
  double distance_mm = 0;            // the search for the way out; 0: the mean boundary edge
  bool split_labels = false;         // the mesh's labels become bodies (several organs in one mesh)
  std::vector<HalfSpace> split_planes;  // LPS mm: each plane splits the mesh into the bodies either side
  double gap_mm = 0;                 // a slab this thick around each plane taken out: the bodies start apart
};

// kind: vessel (sim/vessel/vessel_engine.h), from the scenario's `vessel:` section; the wall's E, nu and
// density are the material section's.
struct VesselSpec {
  double wall_thickness_mm = 0;   // (0, 50] mm, required
  int spokes = 16;                // vertices per ring of the surface, [3, 1024]
  VesselSkinning skinning = VesselSkinning::rmf;  // rmf | spokes (the paper's eq. 15-16)
  bool blood_filled = true;       // the blood in the lumen adds to the mass (vessel_calibration.h)
  int newton_iterations = 6;      // Gauss-Newton iterations per step at most, [1, 100]
};

// One material of a model with several (material.labels, material.inclusions; kind: fem and
// explicit_springs): its preset and values, and for kind: fem its law and the law's constants.
struct ElementMaterial {
  Material material;
  FemLaw law = FemLaw::neo_hookean;
  std::array<double, kFemLawConstants> constants{};
  std::string field;  // "material.labels.2", "material.inclusions[0]": for messages
};

// material.labels: the material of the elements (tets, or grid cells) of one tissue label.
struct LabelMaterial : ElementMaterial {
  uint16_t label = 0;
};

// material.inclusions: a sphere of another material inside the tissue (a tumour, a calcification): the
// elements whose centroid (tets) or centre (grid cells) lies inside it take its material, over their label's.
struct InclusionMaterial : ElementMaterial {
  PointSpec centre;        // position_mm (LPS) or at_fraction (of the tet mesh's or the grid's rest bounding box)
  double radius_mm = 0;    // > 0
};

// Bounds of the time section (scenario.cpp): simulated time, the smallest step, output frames.
inline constexpr double kMaxDurationS = 86400;
inline constexpr double kMinStepS = 1e-9;
inline constexpr double kMaxFrames = 100000;

struct Scenario {
  std::filesystem::path file;       // the scenario file (as given)
  std::string name;
  ModelKind model = ModelKind::spring_grid;
  SpringSource springs_from = SpringSource::grid;
  std::filesystem::path grid;       // occupancy grid file (ctsurg-grid); required except for kind: fem
                                    // (which does not read it); scenario_model.h says what a model reads
  std::filesystem::path surface;    // surface file (ctsurg-surface/-normalmap) on that grid; optional
  std::filesystem::path tetmesh;    // tet mesh file (ctsurg-tetmesh): kind fem, or springs_from: tetmesh
  std::filesystem::path centerline; // centerline file (ctsurg-centerline): kind vessel (reads nothing else)
  VesselSpec vessel;                // kind vessel
  CouplingMode coupling = CouplingMode::trilinear;
  FemLaw material_law = FemLaw::neo_hookean;  // kind: fem; material.law
  std::array<double, kFemLawConstants> law_constants{};  // kind: fem; the law's own (material.c10_pa, ...), Pa
  FemSolver fem_solver = FemSolver::dynamic;                       // kind: fem
  int fem_order = 1;  // kind: fem; elements: linear (1, 4-node tets) | quadratic (2, 10-node; static and implicit)
  bool mass_from_fraction = false;
  bool close_cuts = true;           // spring models: close the holes a cut leaves in the surface (hole_filling.h)
  Material material;                // preset, possibly with explicit overrides (with material.labels: the first label's)
  std::vector<LabelMaterial> label_materials;  // kind: fem, material.labels (increasing labels); empty: one material
  std::vector<InclusionMaterial> inclusions;   // kind: fem, material.inclusions (in order: a later one wins)
  double damping_per_s = 0;         // mass-proportional damping rate alpha, 1/s (Verlet factor alpha dt)
  double stiffness_damping_s = 0;   // fem implicit: Rayleigh stiffness damping beta, s
  std::array<double, 3> gravity{0, 0, 0};  // mm/s^2, LPS
  std::vector<FixedRegionSpec> fixed;
  std::vector<ToolAction> tools;
  double duration_s = 0;            // (0, kMaxDurationS]
  double dt_s = 0;                  // 0 = auto (safety_factor * critical step), else >= kMinStepS
  FemImplicitScheme implicit_scheme = FemImplicitScheme::backward_euler;  // fem implicit: time.integrator
  double safety_factor = 0.5;       // (0, 1]
  int max_step_halvings = 0;        // on instability: restart from the last frame with dt / 2, this often
  double frame_interval_s = 0;      // output frame every ...; > 0
  bool write_particles = false;     // also store every particle's position per frame
  std::filesystem::path trajectory; // output trajectory (.h5)
  std::vector<RenderRequest> render;  // pictures for the pipeline to make (none: no rendering)
  SolverSpec solver;                // fem static and implicit
  ContactSpec contact;              // fem dynamic
  std::string backend = "cpu";      // cpu | cuda | auto
  int threads = 0;                  // 0 = automatic
};

// Parses scenario text. `file` names it in messages; relative paths are resolved against `base_dir`.
Scenario parse_scenario(const std::string& text, const std::filesystem::path& file, const std::filesystem::path& base_dir);
// Reads and parses a scenario file (InputError naming it when it cannot be read).
Scenario read_scenario_file(const std::filesystem::path& path);
// The file's text, checked as read_scenario_file checks it (a readable file of at most 1 MiB), for a
// caller that keeps the text too (a live session saves it with the user's tools).
std::string read_scenario_text(const std::filesystem::path& path);

// What the scenario reads and writes, as JSON for the pipeline (ctsurg-sim --describe): the model
// kind, the input files it reads (grid, surface, tetmesh: model_inputs in scenario_model.h), the
// trajectory, and the render requests.
std::string describe_scenario(const Scenario& scenario);

const char* to_string(ModelKind kind);

}  // namespace ctsurg::sim
