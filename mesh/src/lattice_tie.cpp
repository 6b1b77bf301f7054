#include "ctsurg/mesh/lattice_tie.h"

#include "ctsurg/core/error.h"

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace ctsurg {

namespace {

// The inside node nearest to `x` (LPS mm) among the nodes with every index within `r` of `c`.
// Returns false when there is none.
bool nearest_inside(const Volume<float>& field, double iso, const Eigen::Matrix3d& M, const Eigen::Vector3d& origin,
                    const Eigen::Vector3d& x, const std::array<int64_t, 3>& c, int64_t r, std::array<int64_t, 3>& best) {
  const auto& d = field.geometry.dims;
  double best_d2 = std::numeric_limits<double>::infinity();
  std::array<int64_t, 3> lo{}, hi{};
  for (std::size_t a = 0; a < 3; ++a) {
    lo[a] = std::max<int64_t>(c[a] - r, 0);
    hi[a] = std::min<int64_t>(c[a] + 1 + r, d[a] - 1);
  }
  for (int64_t k = lo[2]; k <= hi[2]; ++k)
    for (int64_t j = lo[1]; j <= hi[1]; ++j)
      for (int64_t i = lo[0]; i <= hi[0]; ++i) {
        if (!(double(field(i, j, k)) >= iso)) continue;
        const double d2 = (origin + M * Eigen::Vector3d(double(i), double(j), double(k)) - x).squaredNorm();
        if (d2 < best_d2) {  // strict: ties keep the first node in (k, j, i) order, deterministic
          best_d2 = d2;
          best = {i, j, k};
        }
      }
  return std::isfinite(best_d2);
}

}  // namespace

void tie_surface_to_lattice(SurfaceMesh& mesh, const Volume<float>& field) {
  const ImageGeometry& g = field.geometry;
  if (!mesh.lattice.same_lattice(g)) {
    throw InputError("mesh", "lattice", "the surface was not extracted from this field's lattice");
  }
  const auto nv = static_cast<std::size_t>(mesh.vertex_count());
  mesh.grid_cell.resize(3 * nv);
  mesh.grid_weights.resize(8 * nv);
  mesh.nearest_node.resize(3 * nv);
  const Eigen::Matrix3d M = g.index_to_world_matrix();
  const Eigen::Vector3d origin = g.origin;
  const int64_t max_r = std::max({g.dims[0], g.dims[1], g.dims[2]});
#pragma omp parallel for schedule(static)
  for (int64_t v = 0; v < int64_t(nv); ++v) {
    const auto sv = static_cast<std::size_t>(v);
    const Eigen::Vector3d x(mesh.vertices[3 * sv], mesh.vertices[3 * sv + 1], mesh.vertices[3 * sv + 2]);
    const Eigen::Vector3d ijk = g.world_to_index(x);
    std::array<int64_t, 3> cell{};
    double frac[3];
    for (std::size_t a = 0; a < 3; ++a) {
      const auto idx = static_cast<Eigen::Index>(a);
      cell[a] = std::clamp<int64_t>(static_cast<int64_t>(std::floor(ijk[idx])), 0, g.dims[a] - 2);
      frac[a] = ijk[idx] - double(cell[a]);
      mesh.grid_cell[3 * sv + a] = static_cast<int32_t>(cell[a]);
    }
    for (std::size_t c = 0; c < 8; ++c) {
      double w = 1.0;
      for (std::size_t a = 0; a < 3; ++a) w *= ((c >> a) & 1) ? frac[a] : 1.0 - frac[a];
      mesh.grid_weights[8 * sv + c] = static_cast<float>(w);
    }
    std::array<int64_t, 3> best = cell;
    for (int64_t r = 1; r <= max_r; r *= 2)
      if (nearest_inside(field, mesh.iso, M, origin, x, cell, r, best)) break;
    for (std::size_t a = 0; a < 3; ++a) mesh.nearest_node[3 * sv + a] = static_cast<int32_t>(best[a]);
  }
}

}  // namespace ctsurg
