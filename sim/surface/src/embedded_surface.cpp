#include "ctsurg/sim/surface/embedded_surface.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/surface/surface_cutting.h"

#include <string>
#include <utility>

namespace ctsurg::sim {

EmbeddedSurface::EmbeddedSurface(SurfaceCoupling coupling, std::vector<uint32_t> triangles)
    : coupling_(std::move(coupling)), triangles_(std::move(triangles)) {
  if (triangles_.size() % 3 != 0) throw InputError("surface", "triangles", "expected #F x 3 vertex ids");
  const auto nv = static_cast<uint64_t>(coupling_.vertex_count());
  for (const uint32_t v : triangles_) {
    if (v >= nv) throw InputError("surface", "triangles", "vertex id " + std::to_string(v) + " out of range (" + std::to_string(nv) + " vertices)");
  }
}

void EmbeddedSurface::move(const ParticleState& positions, const std::vector<Real>& rest, std::vector<float>& vertices,
                           int threads) const {
  move_surface(coupling_, positions, rest, vertices, threads);
}

int64_t EmbeddedSurface::cut(const Triangle& blade, const std::vector<float>& vertices, const ParticleState& positions) {
  return cut_surface(triangles_, coupling_, vertices, positions, blade).triangles_removed;
}

int64_t EmbeddedSurface::cut_triangles(const Triangle& blade, const std::vector<float>& vertices) {
  return remove_crossed_triangles(triangles_, vertices, blade);
}

void EmbeddedSurface::retie(std::vector<int32_t> particles) {
  if (particles.size() != coupling_.particles.size()) throw InputError("surface", "particles", "expected #V x 8 ties");
  coupling_.particles = std::move(particles);
}

}  // namespace ctsurg::sim
