#include "ctsurg/sim/surface/embedded_surface.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/surface/hole_filling.h"
#include "ctsurg/sim/surface/surface_cutting.h"

#include <string>
#include <utility>

namespace ctsurg::sim {

EmbeddedSurface::EmbeddedSurface(SurfaceCoupling coupling, std::vector<uint32_t> triangles)
    : coupling_(std::move(coupling)), cut_(std::move(triangles)) {
  if (cut_.size() % 3 != 0) throw InputError("surface", "triangles", "expected #F x 3 vertex ids");
  const auto nv = static_cast<uint64_t>(coupling_.vertex_count());
  for (const uint32_t v : cut_) {
    if (v >= nv) throw InputError("surface", "triangles", "vertex id " + std::to_string(v) + " out of range (" + std::to_string(nv) + " vertices)");
  }
  triangles_ = cut_;
}

void EmbeddedSurface::move(const ParticleState& positions, const std::vector<Real>& rest, std::vector<float>& vertices,
                           int threads) const {
  move_surface(coupling_, positions, rest, vertices, threads);
}

int64_t EmbeddedSurface::cut(const Triangle& blade, const std::vector<float>& vertices, const ParticleState& positions) {
  const int64_t removed = cut_surface(cut_, coupling_, vertices, positions, blade).triangles_removed;
  if (removed > 0) triangles_ = cut_;  // open until close_cut_holes() re-closes it
  return removed;
}

int64_t EmbeddedSurface::cut_triangles(const Triangle& blade, const std::vector<float>& vertices) {
  const int64_t removed = remove_crossed_triangles(cut_, vertices, blade);
  if (removed > 0) triangles_ = cut_;  // open until close_cut_holes() re-closes it
  return removed;
}

int64_t EmbeddedSurface::remove_tied_to(const std::vector<uint8_t>& gone) {
  const int64_t nv = vertex_count();
  std::vector<uint8_t> vertex_gone(static_cast<size_t>(nv), 0);
  for (int64_t v = 0; v < nv; ++v) {
    for (size_t k = 0; k < 8; ++k) {
      const int32_t p = coupling_.particles[8 * static_cast<size_t>(v) + k];
      if (p < 0 || !(coupling_.weights[8 * static_cast<size_t>(v) + k] > 0)) continue;
      if (static_cast<size_t>(p) >= gone.size()) {
        throw InputError("surface", "gone", "node " + std::to_string(p) + " is beyond the " + std::to_string(gone.size()) + " flags");
      }
      if (gone[static_cast<size_t>(p)]) vertex_gone[static_cast<size_t>(v)] = 1;
    }
  }
  return remove_vertices(vertex_gone);
}

int64_t EmbeddedSurface::remove_vertices(const std::vector<uint8_t>& gone) {
  if (static_cast<int64_t>(gone.size()) != vertex_count()) throw InputError("surface", "gone", "expected one flag per vertex");
  size_t kept = 0;
  for (size_t f = 0; f < cut_.size(); f += 3) {
    if (gone[cut_[f]] || gone[cut_[f + 1]] || gone[cut_[f + 2]]) continue;
    for (size_t c = 0; c < 3; ++c) cut_[kept + c] = cut_[f + c];
    kept += 3;
  }
  const int64_t removed = static_cast<int64_t>(cut_.size() - kept) / 3;
  cut_.resize(kept);
  if (removed > 0) triangles_ = cut_;  // open until close_cut_holes() re-closes it
  return removed;
}

void EmbeddedSurface::set_close_cuts(bool close) {
  close_cuts_ = close;
  if (!close) return;
  weld_ = weld_coincident(coupling_.rest_vertices);
  own_boundary_ = boundary_edges(cut_, weld_);
}

int64_t EmbeddedSurface::close_cut_holes(const std::vector<float>& vertices) {
  if (!close_cuts_) return 0;
  if (static_cast<int64_t>(vertices.size()) != 3 * vertex_count()) throw InputError("surface", "vertices", "expected #V x 3");
  const std::vector<uint32_t> fill = fill_cut_holes(cut_, vertices, own_boundary_, weld_);
  triangles_ = cut_;
  triangles_.insert(triangles_.end(), fill.begin(), fill.end());
  return static_cast<int64_t>(fill.size() / 3);
}

void EmbeddedSurface::retie(std::vector<int32_t> particles) {
  if (particles.size() != coupling_.particles.size()) throw InputError("surface", "particles", "expected #V x 8 ties");
  coupling_.particles = std::move(particles);
}

}  // namespace ctsurg::sim
