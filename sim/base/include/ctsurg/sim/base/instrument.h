// A rigid instrument: a closed triangle mesh (a forceps jaw, a retractor blade, a probe rod, a scalpel:
// data_samples/instruments/) that moves along a scenario's timeline with a position and an orientation
// (scenario/tool_timeline.h) and pushes the tissue out of itself (the spring models project their
// particles out, the FEM's explicit dynamics its nodes: springs/instrument_contact.h,
// fem/fem_explicit_dynamics.h).
//
// The mesh is given in the instrument's own frame, in mm, with the point the path moves at its origin
// (the tip, for a probe). Loading checks what makes contact well defined: a closed surface (every edge
// shared by exactly two faces, in opposite directions, so the inside is defined), no degenerate faces
// (a face whose height is under 1e-5 of the mesh's size has no normal), a size a surgical instrument
// can have (0.5 mm to 500 mm across) and at most kMaxInstrumentFaces faces. A mesh whose faces all
// point inwards is flipped (the note says so); one with mixed orientation is refused, as the edge rule
// finds it.
//
// Contact uses the signed distance baked on a grid in the instrument's frame (signed_distance_grid.h):
// one trilinear read per tissue point per step, whatever the mesh's size, on the CPU or CUDA. A rigid
// body needs no hashing of its own primitives each step (its shape never changes); the spatial hash
// (sim/collision) is for deformable surfaces meeting each other.
//
// Units: mm.
#pragma once

#include "ctsurg/core/triangle_mesh_file.h"
#include "ctsurg/sim/base/kernels/instrument_contact_impl.h"
#include "ctsurg/sim/base/rigid_pose.h"
#include "ctsurg/sim/base/signed_distance_grid.h"

#include <filesystem>
#include <functional>
#include <memory>
#include <string>

namespace ctsurg::sim {

inline constexpr int64_t kMaxInstrumentFaces = 200'000;
inline constexpr double kMinInstrumentSizeMm = 0.5, kMaxInstrumentSizeMm = 500;
inline constexpr int64_t kMaxInstrumentGridNodes = 16'000'000;

struct Instrument {
  std::string name;            // the file it came from (messages)
  TriangleMesh mesh;           // the instrument's frame, mm, faces wound outwards
  SignedDistanceGrid distance; // its signed distance, same frame
  double volume_mm3 = 0;
  double size_mm = 0;          // its bounding box's diagonal
  double thickness_mm = 0;     // 2 volume / area: a plate's thickness, a rod's radius
};

// Checks `mesh` as an instrument (the rules above); InputError(file, field, problem) naming the
// offending face, edge or size. Returns the mesh wound outwards; `note` hears of a flip (may be empty).
TriangleMesh checked_instrument_mesh(TriangleMesh mesh, const std::string& file,
                                     const std::function<void(const std::string&)>& note = {});

// An instrument from a checked mesh: its distance grid with `spacing_mm` between nodes (0: automatic,
// a fifth of its thickness 2 V / A, within 0.05 .. 0.5 mm, coarsened until the grid has at most
// kMaxInstrumentGridNodes nodes).
Instrument make_instrument(TriangleMesh mesh, const std::string& name, double spacing_mm = 0,
                           const std::function<void(const std::string&)>& note = {});

// Reads (core/triangle_mesh_file.h), checks and bakes an instrument file.
std::shared_ptr<const Instrument> load_instrument(const std::filesystem::path& path, double spacing_mm = 0,
                                                  const std::function<void(const std::string&)>& note = {});

// The kernels' view of an instrument at a pose (rotation q, translation `centre` mm, the run's
// frame); `instrument` must outlive the view.
InstrumentView instrument_view(const Instrument& instrument, const Quaternion& q, const std::array<double, 3>& centre);

// InputError(where, field, ...) unless `view` has a distance grid (at least 2 nodes an axis, spacing > 0):
// the dispatchers' check before a kernel reads it.
void check_instrument_view(const InstrumentView& view, const std::string& where, const std::string& field);

}  // namespace ctsurg::sim
