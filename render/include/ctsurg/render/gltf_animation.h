// A trajectory as an animated glTF 2.0 file (.glb, or .gltf with a .bin beside it) that plays in any
// glTF viewer, browsers included: the deformation as morph targets keyed in time, the surface's normal
// map as the material's normal texture, in the frame of every glTF ctsurg writes (gltf_frame.h: metres,
// +Y superior, +Z anterior, +X the patient's left, baked into the vertices) and core glTF 2.0 only (no
// extensions), so the Khronos validator passes it without errors or warnings.
//
// Layout (docs/formats.md, "Animated glTF"), for the exported frames s_0 < s_1 < ... < s_{n-1}:
//   - One set of vertex attributes, shared by every mesh: POSITION, NORMAL (and, with a normal map,
//     TANGENT and TEXCOORD_0) of frame s_0, the base. Normals and tangents are the renderer's
//     (deformed_tangent_frames.h): the surface file's frames rotated with the tissue. Positions are
//     relative to the centre c of the base's bounding box, and every node is translated by c (its
//     only transform besides the scale below): world position = c + POSITION + morphs.
//   - Morph target i (i = 1 .. n-1) is frame s_i minus the base: POSITION (metres) and NORMAL deltas;
//     tangents are not morphed (three.js ignores TANGENT targets, and they would add half the size).
//     A target that moves no vertex is an accessor without data (zeros); one that moves few is a
//     sparse accessor, whichever is smaller than the dense array.
//   - One animation: a `weights` channel, LINEAR, keyed at the frames' times (seconds from s_0 times
//     time_scale), whose value at key i is one-hot on target i (all zero at the base), so between two
//     keys exactly two weights are non-zero and the vertices move linearly from one frame to the next.
//     One more key, one frame interval after the last frame, holds the last frame, so a viewer playing
//     in a loop shows it as long as the others (the clip's clock wraps to 0 at its end).
//   - Topology changes (cuts): the frames split into runs of one topology. Each run is a node with a
//     mesh of its own triangles (and its own morph targets: those of its frames), and a `scale`
//     channel, STEP, shows one node at a time (1 from its first frame's time until the next run's, 0
//     otherwise; nodes after the first are also 0 at rest, so a viewer without animation shows the
//     base). Between a run's last frame and the next run's first, the old topology holds its last
//     frame. The triangles that close a cut's holes (/trajectory/surface/closing_triangles) are a
//     second primitive in the wound's dark red without the normal map, as the renderer draws them,
//     and the tissue of a cut topology is double-sided so the incision's inside shows.
// Tools (grab spheres, blades, instruments, stitches) are not exported.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "ctsurg/core/atomic_output.h"
#include "ctsurg/core/surface_mesh_file.h"
#include "ctsurg/core/trajectory_file.h"

namespace ctsurg {

struct GltfAnimationOptions {
  std::vector<int64_t> frames;  // trajectory frames to export, ascending and unique; empty: every frame
  double time_scale = 1.0;      // playback seconds per simulated second (> 0): 10 plays ten times slower
  bool normal_map = true;       // the surface's normal map as the material's normal texture (when it has one)
  std::string trajectory_name;  // names the trajectory in messages (e.g. its file)
};

// What an export holds (for logs and tests).
struct GltfAnimationSummary {
  int64_t frames = 0;          // exported frames (1: a still surface, no animation)
  int64_t morph_targets = 0;   // over all meshes: frames - 1
  int64_t sparse_targets = 0;  // morph target accessors stored sparse or empty (POSITION and NORMAL counted apart)
  int64_t nodes = 0;           // one per run of one topology
  int64_t bytes = 0;           // the files' sizes together
};

// "glb", "gltf", or "" when `path`'s suffix (any case) is neither.
std::string gltf_animation_format(const std::filesystem::path& path);

// The files of the export of `trajectory` (frames options.frames, or all; nullptr: the surface alone,
// no animation) simulated on `surface` to `output`, made in memory under their final names: (file
// name, bytes), the output first, then, for .gltf, NAME.bin which it names. `surface` is the rest
// surface (#V vertices, LPS mm, with normals; uvs, tangents and a normal map optional).
// InputError(output, "suffix", ...) for another suffix; InputError(options.trajectory_name, field, ...)
// when the trajectory does not fit the surface (vertex count), a frame is out of range or out of
// order, two exported frames have the same time, or a frame's topology has no triangles;
// InputError("--time-scale", ...) unless time_scale is finite and > 0.
std::vector<std::pair<std::string, std::string>> export_gltf_animation(const std::filesystem::path& output,
                                                                       const SurfaceMesh& surface,
                                                                       const Trajectory* trajectory,
                                                                       const GltfAnimationOptions& options = {},
                                                                       GltfAnimationSummary* summary = nullptr);

// Every file an export to `output` writes: the output, and for .gltf NAME.bin. For check_output_paths().
std::vector<std::filesystem::path> gltf_animation_files(const std::filesystem::path& output);

// export_gltf_animation(), each file written (every error checked) to its temporary name in `unit`;
// the caller commits the unit. Returns the bytes of the output's own file (the .glb, or the .gltf's
// JSON).
std::string add_gltf_animation(OutputUnit& unit, const std::filesystem::path& output, const SurfaceMesh& surface,
                               const Trajectory* trajectory, const GltfAnimationOptions& options = {},
                               GltfAnimationSummary* summary = nullptr);

}  // namespace ctsurg
