// The trajectory: what a simulation run (ctsurg-sim) produces and the renderer reads. The surface's
// vertices at each output frame, the surface's topology over time (a cut removes triangles), the
// tools' positions, and per-frame metrics:
//
//   /provenance
//   /trajectory                            attributes: scenario, model, surface_file, surface_sha256,
//                                          dt_s, frames, vertices, frame "LPS", units "mm"
//   /trajectory/time                       (F)        float64  s
//   /trajectory/surface/rest_vertices      (V, 3)     float32  LPS mm (the surface file's vertices)
//   /trajectory/surface/vertices           (F, V, 3)  float32  LPS mm
//   /trajectory/surface/topologies/<k>     (T_k, 3)   uint32   triangles, k = "0", "1", ... in order
//   /trajectory/surface/topology_of_frame  (F)        int32    the topology each frame uses
//   /trajectory/surface/closing_triangles  (K)        int64    optional, one per topology: how many of its last
//                                          triangles close the holes a cut left (drawn as the wound's inside)
//   /trajectory/surface/vertex_region      (F, V)     uint8    optional: the FEM local region at each frame
//                                          (sim/fem/fem_local_region.h), per surface vertex: 0 outside, 1 in
//                                          the region, 2 on its interface (files without it read as empty)
//   /trajectory/metrics/<name>             (F)        float64  attribute units (e.g. kinetic_energy, nJ)
//   /trajectory/tools/spheres              (F, S, 4)  float64  centre xyz LPS mm, radius mm (0: inactive)
//                                          attribute kinds: "grab;probe;..." (one per sphere)
//   /trajectory/tools/sphere_loads         (F, S, 7)  float64  optional: the load each sphere tool exerts on the
//                                          tissue (SimulationEngine::tool_load): measured 1/0, force xyz (N, LPS),
//                                          moment xyz about the sphere's centre (N mm); the tissue pulls the tool
//                                          with the opposite. Written when the engine measured some (files without
//                                          it read as empty)
//   /trajectory/tools/blades               (F, B, 7)  float64  edge end a xyz, end b xyz (LPS mm), active 1/0
//   /trajectory/tools/instruments/<k>/vertices   (V_k, 3) float32 the instrument's mesh, its own frame, mm
//   /trajectory/tools/instruments/<k>/triangles  (T_k, 3) uint32  (attribute name: the mesh file)
//   /trajectory/tools/instrument_poses     (F, I, 8)  float64  active 1/0, rotation w x y z (unit), translation
//                                          LPS mm: a vertex q of instrument k is at R q + t (optional: I = 0)
//   /trajectory/tools/stitches             (F, K, 7)  float64  a suture's stitch: end a xyz, end b xyz (LPS mm, the
//                                          points it joins, moving with the tissue), placed 1/0 (optional: K = 0;
//                                          files without it read as K = 0)
//   /trajectory/particles/rest_positions   (P, 3)     float32  optional: the model's nodes at rest
//   /trajectory/particles/positions        (F, P, 3)  float32  optional: the nodes at each frame
//   /trajectory/particles/elements         (E, 4|10)  int32    optional, with the particles: an FEM model's tets
//                                          over them (10 nodes: quadratic, VTK_QUADRATIC_TETRA's order), so
//                                          that ParaView opens the particles as the FE mesh (XDMF Tetrahedron
//                                          or Tetrahedron_10) with its displacement
//
// plus an XDMF sidecar: a temporal collection of the surface (and the particles as a point cloud),
// with the displacement as a vector attribute (and the local region, when present, as a scalar
// attribute), which ParaView plays as an animation.
#pragma once

#include "ctsurg/core/provenance.h"

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace ctsurg {

struct TrajectoryMetric {
  std::string name;            // e.g. "kinetic_energy"
  std::string units;           // e.g. "nJ"
  std::vector<double> values;  // one per frame
};

// A rigid instrument's shape (sim/base/instrument.h), for the renderer to draw at its poses.
struct TrajectoryInstrument {
  std::string name;                 // the mesh file the scenario named
  std::vector<float> vertices;      // V x 3 mm, the instrument's own frame
  std::vector<uint32_t> triangles;  // T x 3
};

struct Trajectory {
  std::string scenario;        // the scenario's name
  std::string model;           // the model kind, e.g. "spring_grid"
  std::string surface_file;    // the surface the scenario named (as written in the scenario)
  std::string surface_sha256;  // of that file's bytes, so a renderer can check it has the same surface
  double dt_s = 0;             // the integration step

  std::vector<double> time;                        // F, s
  std::vector<float> rest_vertices;                // V x 3, LPS mm
  std::vector<float> vertices;                     // F x V x 3, LPS mm
  std::vector<std::vector<uint32_t>> topologies;   // each T_k x 3
  std::vector<int32_t> topology_of_frame;          // F, index into topologies
  std::vector<int64_t> closing_triangles;          // one per topology (its last triangles closing cut holes), or empty
  std::vector<uint8_t> vertex_region;              // F x V: 0 outside, 1 local region, 2 its interface; or empty
  std::vector<TrajectoryMetric> metrics;
  std::vector<std::string> sphere_kinds;           // S: "grab" or "probe"
  std::vector<double> spheres;                     // F x S x 4
  std::vector<double> sphere_loads;                // F x S x 7: measured, force N, moment N mm; or empty
  std::vector<double> blades;                      // F x B x 7
  std::vector<TrajectoryInstrument> instruments;   // I
  std::vector<double> instrument_poses;            // F x I x 8: active, w x y z, t (LPS mm)
  std::vector<double> stitches;                    // F x K x 7: end a, end b (LPS mm), placed 1/0; or empty
  std::vector<float> rest_particles;               // P x 3 or empty
  std::vector<float> particles;                    // F x P x 3 or empty
  std::vector<int32_t> elements;                   // E x element_nodes particle ids, or empty
  int32_t element_nodes = 0;                       // 4 or 10 with elements, else 0

  int64_t frame_count() const { return static_cast<int64_t>(time.size()); }
  int64_t vertex_count() const { return static_cast<int64_t>(rest_vertices.size() / 3); }
  int64_t sphere_count() const { return static_cast<int64_t>(sphere_kinds.size()); }
  int64_t blade_count() const { return frame_count() ? static_cast<int64_t>(blades.size()) / (7 * frame_count()) : 0; }
  int64_t stitch_count() const { return frame_count() ? static_cast<int64_t>(stitches.size()) / (7 * frame_count()) : 0; }
  int64_t particle_count() const { return static_cast<int64_t>(rest_particles.size() / 3); }
  int64_t element_count() const { return element_nodes > 0 ? static_cast<int64_t>(elements.size()) / element_nodes : 0; }
  // The metric called `name`, or nullptr.
  const TrajectoryMetric* metric(const std::string& name) const;
  // Frame f's vertices (V x 3) and triangles.
  const float* frame_vertices(int64_t f) const { return vertices.data() + f * vertex_count() * 3; }
  const std::vector<uint32_t>& frame_triangles(int64_t f) const { return topologies[topology_of_frame[f]]; }
  // Frame f's local-region flags (V), or nullptr when the trajectory has none.
  const uint8_t* frame_region(int64_t f) const { return vertex_region.empty() ? nullptr : vertex_region.data() + f * vertex_count(); }
};

// Checks every array's size against F, V, S, B, I, P and the triangles' vertex ids (and the poses'
// rotations: unit quaternions; the region's flags: 0, 1 or 2); InputError(file,
// "/trajectory/...", ...) naming the first inconsistency (file: the name used in messages).
void validate_trajectory(const Trajectory& trajectory, const std::string& file);
// Writes `path` and its .xdmf sidecar atomically (validated first).
void write_trajectory_file(const std::filesystem::path& path, const Trajectory& trajectory, const Provenance& provenance);
// Reads and validates a trajectory file; InputError naming the file and dataset when it is not one.
Trajectory read_trajectory_file(const std::filesystem::path& path);

}  // namespace ctsurg
