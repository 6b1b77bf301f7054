#include "ctsurg/sim/surface/surface_coupling.h"

#include "ctsurg/sim/surface/kernels/surface_coupling_impl.h"
#include "surface_cpu_kernels.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/base/lattice_particles.h"

#include <cmath>
#include <string>

namespace ctsurg::sim {
namespace {

// Index offset of the surface lattice's node (0, 0, 0) in the model lattice; throws unless the lattices
// share spacing and direction and the surface's origin is on a model node.
std::array<int64_t, 3> lattice_offset(const ImageGeometry& surface, const ImageGeometry& grid) {
  const auto bad = [](const std::string& what) { throw InputError("surface", "lattice", what); };
  if ((surface.spacing - grid.spacing).cwiseAbs().maxCoeff() > 1e-4 * grid.spacing.maxCoeff())
    bad("spacing differs from the grid's: the surface was not extracted from this grid");
  if ((surface.direction - grid.direction).cwiseAbs().maxCoeff() > 1e-6)
    bad("direction differs from the grid's: the surface was not extracted from this grid");
  const Eigen::Vector3d o = grid.world_to_index(surface.origin);
  std::array<int64_t, 3> offset{};
  for (int a = 0; a < 3; ++a) {
    offset[a] = std::llround(o[a]);
    if (std::abs(o[a] - static_cast<double>(offset[a])) > 1e-3)
      bad("origin is not on a node of the grid's lattice (offset " + std::to_string(o[a]) + " nodes on axis " +
          std::to_string(a) + "): the surface was not extracted from this grid");
  }
  return offset;
}

}  // namespace

SurfaceCoupling couple_surface(const SurfaceMesh& mesh, const ImageGeometry& lattice, const std::vector<int64_t>& particle_cells,
                               CouplingMode mode) {
  const int64_t nv = mesh.vertex_count();
  if (static_cast<int64_t>(mesh.grid_cell.size()) != 3 * nv || static_cast<int64_t>(mesh.grid_weights.size()) != 8 * nv ||
      static_cast<int64_t>(mesh.nearest_node.size()) != 3 * nv)
    throw InputError("surface", "grid_cell", "the surface has no complete lattice tie (grid_cell, grid_weights, nearest_node)");
  const auto off = lattice_offset(mesh.lattice, lattice);
  SurfaceCoupling c;
  c.mode = mode;
  c.particles.assign(static_cast<std::size_t>(8 * nv), -1);
  c.weights.assign(static_cast<std::size_t>(8 * nv), Real(0));
  c.rest_vertices.assign(mesh.vertices.begin(), mesh.vertices.end());
  for (int64_t v = 0; v < nv; ++v) {
    const int32_t* cell = &mesh.grid_cell[static_cast<std::size_t>(3 * v)];
    const int32_t* node = &mesh.nearest_node[static_cast<std::size_t>(3 * v)];
    const int32_t nearest = lattice_particle(lattice, particle_cells, node[0] + off[0], node[1] + off[1], node[2] + off[2]);
    int32_t corner[8];
    double w[8], sum = 0;
    int best = -1;
    for (int k = 0; k < 8; ++k) {
      corner[k] = lattice_particle(lattice, particle_cells, cell[0] + (k & 1) + off[0], cell[1] + (k >> 1 & 1) + off[1], cell[2] + (k >> 2 & 1) + off[2]);
      w[k] = corner[k] >= 0 ? mesh.grid_weights[static_cast<std::size_t>(8 * v + k)] : 0.0;
      sum += w[k];
      if (corner[k] >= 0 && (best < 0 || w[k] > w[best])) best = k;
    }
    const std::size_t base = static_cast<std::size_t>(8 * v);
    if (mode == CouplingMode::trilinear && sum > 1e-6) {
      for (int k = 0; k < 8; ++k) c.particles[base + k] = corner[k], c.weights[base + k] = static_cast<Real>(w[k] / sum);
      continue;
    }
    // Nearest particle: the nearest inside node, else the corner particle with the largest weight.
    const int32_t p = nearest >= 0 ? nearest : (best >= 0 ? corner[best] : -1);
    if (p < 0)
      throw InputError("surface", "vertex " + std::to_string(v),
                       "neither its nearest inside node nor a corner of its cell is a particle of the grid");
    c.particles[base] = p;
    c.weights[base] = Real(1);
  }
  return c;
}

void move_surface(const SurfaceCoupling& coupling, const ParticleState& state, const std::vector<Real>& rest_positions,
                  std::vector<float>& vertices, int threads) {
  if (rest_positions.size() != 3 * static_cast<std::size_t>(state.count()))
    throw InputError("move_surface", "rest_positions", "expected 3 x the state's particle count");
  for (int32_t p : coupling.particles)
    if (p >= state.count()) throw InputError("move_surface", "coupling", "names a particle the state does not have");
  vertices.resize(coupling.rest_vertices.size());
  const SurfaceCouplingView view{coupling.particles.data(), coupling.weights.data(), coupling.rest_vertices.data(),
                                 state.x.data(), state.y.data(), state.z.data(), rest_positions.data(),
                                 vertices.data(), coupling.vertex_count()};
  cpu::move_surface(view, threads);
}

}  // namespace ctsurg::sim
