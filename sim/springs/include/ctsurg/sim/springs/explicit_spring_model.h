// The spring-mass model with explicit connections (Mosegaard & Sorensen 2005, section 2.5.1): any
// list of springs (i, j, stiffness, rest length, damping), e.g. the edges of a tetrahedral mesh or
// the 18-neighbour springs of a grid model.
//
// Each spring appears in both endpoints' rows of a CSR adjacency (with its spring id), so the step
// kernel gathers every particle's force from its own row: no atomics, deterministic, each spring
// evaluated twice with opposite signs (as the papers do). Cutting clears a spring's alive flag. The
// CPU also keeps the rows in chunks of 32 particles, slot-major (sliced ELLPACK), so its SIMD lanes run
// across particles (see ExplicitSpringModel::chunk_start).
//
// Units: see particle_state.h (mm, s, g; stiffness g/s^2 = uN/mm; damping g/s).
#pragma once

#include "ctsurg/sim/base/particle_state.h"
#include "ctsurg/sim/base/real.h"
#include "ctsurg/sim/springs/spring_grid_model.h"

#include <cstdint>
#include <functional>
#include <vector>

namespace ctsurg {
struct TetMesh;  // core/tet_mesh_file.h
}

namespace ctsurg::sim {

struct Spring {
  int32_t i = 0, j = 0;      // particle ids, i != j
  double stiffness = 0;      // g/s^2, >= 0
  double rest_length = 0;    // mm, >= 0
  double damping = 0;        // g/s, >= 0, along the spring
};

// What the step kernel sees (trivially copyable).
struct ExplicitSpringView {
  const int32_t* row_offsets;    // #P + 1: particle i's entries are [row_offsets[i], row_offsets[i + 1])
  const int32_t* row_neighbour;  // #E = 2 #S: the other particle of each entry
  const int32_t* row_spring;     // #E: the spring id of each entry
  const Real* stiffness;         // #S g/s^2
  const Real* rest_length;       // #S mm
  const Real* damping;           // #S g/s
  const uint8_t* alive;          // #S 1 = present, 0 = cut
  int32_t count;                 // #P
  // The CPU chunk layout (see ExplicitSpringModel); empty (null) to use the CSR rows only.
  const int64_t* chunk_start;    // #chunks + 1
  const int32_t* ell_neighbour;  // slot-major entries
  const Real* ell_stiffness;
  const Real* ell_rest_length;
  const Real* ell_damping;
  const Real* ell_present;       // 1 = spring there and alive, 0 = padding or cut
};

// Particles per chunk of the explicit model's CPU layout.
constexpr int32_t kExplicitChunk = 32;

struct ExplicitSpringModel {
  std::vector<int32_t> spring_ends;    // #S x 2 (i, j)
  std::vector<Real> stiffness;         // #S g/s^2
  std::vector<Real> rest_length;       // #S mm
  std::vector<Real> damping;           // #S g/s
  std::vector<uint8_t> alive;          // #S
  std::vector<int32_t> row_offsets;    // #P + 1
  std::vector<int32_t> row_neighbour;  // 2 #S, rows sorted by (neighbour, spring id)
  std::vector<int32_t> row_spring;     // 2 #S
  std::vector<Real> rest_positions;    // #P x 3 LPS mm
  std::vector<Real> mass;              // #P g
  bool spring_damping = false;         // some spring has damping > 0 (set by the builders; the step
                                       // then runs the damped kernel)
  // CPU layout (sliced ELLPACK), built once from the rows: particles in chunks of 32 (the last,
  // partial chunk uses the rows); chunk c's entries are [chunk_start[c], chunk_start[c + 1]), slot e
  // of lane k at chunk_start[c] + 32 e + k, e < the chunk's longest row. Each entry copies its row
  // entry's neighbour, stiffness, rest length and damping (padding: the particle itself, present 0),
  // so SIMD lanes run across particles with contiguous loads and only positions are gathered; each
  // particle still sums its row in order (the same bits as the rows). spring_entries holds each
  // spring's two entries, for cutting.
  std::vector<int64_t> chunk_start;
  std::vector<int32_t> ell_neighbour;
  std::vector<Real> ell_stiffness, ell_rest_length, ell_damping, ell_present;
  std::vector<int64_t> spring_entries;  // #S x 2 (-1: in the partial chunk, not in the layout)

  int32_t particle_count() const { return static_cast<int32_t>(mass.size()); }
  int32_t spring_count() const { return static_cast<int32_t>(alive.size()); }
  int64_t alive_spring_count() const;
  ExplicitSpringView view() const;
  ParticleState make_state() const;
};

// Builds the model. rest_positions #P x 3 LPS mm; mass #P g (> 0); springs with 0 <= i, j < #P, i != j.
// Throws InputError("springs", ...) naming the first bad spring, InputError("particles", ...) for bad
// sizes or masses.
ExplicitSpringModel build_explicit_spring_model(const std::vector<Real>& rest_positions, const std::vector<Real>& mass,
                                                const std::vector<Spring>& springs);

// The springs of a grid model as an explicit model: same particles, masses, rest positions, and one
// spring per present grid spring (a, b) with a < b, in order of (a, direction).
ExplicitSpringModel explicit_model_from_grid(const SpringGridModel& grid);

// The edges of a tetrahedral mesh as springs: rest length = edge length, one stiffness and damping for
// all; masses lumped: each tet gives density * volume / 4 to each of its nodes (g/mm^3 * mm^3).
// Throws InputError("tetmesh", ...) for an empty mesh or a node that no tet uses.
ExplicitSpringModel explicit_model_from_tet_mesh(const TetMesh& mesh, double density, double stiffness,
                                                 double damping = 0);
// The same with a stiffness per edge: stiffness(volume, length) in g/s^2 for an edge of rest length
// `length` (mm) whose tets have total volume `volume` (mm^3); spring_calibration.h uses E V / l^2.
ExplicitSpringModel explicit_model_from_tet_mesh(const TetMesh& mesh, double density,
                                                 const std::function<double(double volume, double length)>& stiffness,
                                                 double damping = 0);
// The same with a material per tet (spring_calibration.h's per-label materials): tet t lumps
// tet_density[t] * V_t / 4 (g/mm^3 * mm^3) onto each node, and `volume` passed to stiffness() is the
// weighted volume sum over the edge's tets of tet_weight[t] * V_t. Both vectors #T; densities > 0.
// With every weight 1 and one density this is the overload above, to the bit.
ExplicitSpringModel explicit_model_from_tet_mesh(const TetMesh& mesh, const std::vector<double>& tet_density,
                                                 const std::vector<double>& tet_weight,
                                                 const std::function<double(double volume, double length)>& stiffness,
                                                 double damping = 0);

// Cuts spring s (clears its alive flag and its entries in the CPU layout). Returns false when it was
// already cut. Cut springs only through this function or spring_cutting.h, so the layout follows.
bool cut_explicit_spring(ExplicitSpringModel& model, int32_t s);
// Clears the CPU layout's entries of every spring whose alive flag is 0 (after a cutting kernel).
void sync_cut_springs(ExplicitSpringModel& model);

}  // namespace ctsurg::sim
