#include "ctsurg/sim/base/fixed_regions.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/tet_mesh_file.h"

#include <cmath>
#include <set>
#include <string>

namespace ctsurg::sim {

std::vector<int32_t> particles_in_box(const std::vector<Real>& rest, const Box& box) {
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(box.min[a]) || !std::isfinite(box.max[a]) || box.min[a] > box.max[a])
      throw InputError("fixed region", "box", "min must be <= max and both finite on every axis (axis " + std::to_string(a) + ")");
  std::vector<int32_t> ids;
  for (std::size_t i = 0; i < rest.size() / 3; ++i) {
    bool inside = true;
    for (int a = 0; a < 3; ++a) inside = inside && rest[3 * i + a] >= box.min[a] && rest[3 * i + a] <= box.max[a];
    if (inside) ids.push_back(static_cast<int32_t>(i));
  }
  return ids;
}

std::vector<int32_t> particles_in_half_space(const std::vector<Real>& rest, const HalfSpace& h) {
  const double len = std::sqrt(h.normal[0] * h.normal[0] + h.normal[1] * h.normal[1] + h.normal[2] * h.normal[2]);
  if (!(std::isfinite(len) && len > 0)) throw InputError("fixed region", "half_space", "normal must be finite and non-zero");
  for (double p : h.point)
    if (!std::isfinite(p)) throw InputError("fixed region", "half_space", "point must be finite");
  std::vector<int32_t> ids;
  for (std::size_t i = 0; i < rest.size() / 3; ++i) {
    double s = 0;
    for (int a = 0; a < 3; ++a) s += (rest[3 * i + a] - h.point[a]) * h.normal[a];
    if (s >= 0) ids.push_back(static_cast<int32_t>(i));
  }
  return ids;
}

std::vector<int32_t> nodes_with_label(const TetMesh& mesh, uint16_t label) {
  std::set<int32_t> nodes;
  for (int64_t t = 0; t < mesh.tet_count(); ++t) {
    if (mesh.tet_labels[static_cast<size_t>(t)] != label) continue;
    for (int k = 0; k < 4; ++k) nodes.insert(mesh.tets[static_cast<size_t>(4 * t + k)]);
  }
  return {nodes.begin(), nodes.end()};
}

void fix_particles(ParticleState& state, const std::vector<int32_t>& ids) {
  for (int32_t id : ids) {
    if (id < 0 || id >= state.count())
      throw InputError("fixed region", "particle", std::to_string(id) + " out of range [0, " + std::to_string(state.count()) + ")");
    state.set_fixed(id, true);
  }
}

}  // namespace ctsurg::sim
