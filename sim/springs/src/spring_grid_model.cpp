#include "ctsurg/sim/springs/spring_grid_model.h"

#include "ctsurg/sim/base/lattice_particles.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/memory_guard.h"
#include "ctsurg/core/occupancy_grid_file.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <string>

namespace ctsurg::sim {
namespace {

void require_range(double value, double low, bool positive, const char* field) {
  if (!std::isfinite(value) || value < low || (positive && value <= low))
    throw InputError("material", field,
                     std::string("must be finite and ") + (positive ? "> " : ">= ") + std::to_string(low) +
                         ", got " + std::to_string(value));
}

}  // namespace

int32_t SpringGridModel::particle_at(int64_t i, int64_t j, int64_t k) const { return lattice_particle(lattice, cells, i, j, k); }

int64_t SpringGridModel::spring_count() const {
  int64_t bits = 0;
  for (uint32_t m : spring_mask) bits += std::popcount(m);
  return bits / 2;
}

SpringGridView SpringGridModel::view() const {
  SpringGridView v{};
  v.neighbours = neighbours.data();
  v.spring_mask = spring_mask.data();
  v.chunk_offsets = chunk_offsets.data();
  for (int d = 0; d < kGridDirections; ++d) {
    v.rest_length[d] = rest_length[d];
    v.stiffness[d] = stiffness[d];
    v.damping[d] = damping[d];
  }
  v.count = particle_count();
  return v;
}

ParticleState SpringGridModel::make_state() const { return ParticleState(rest_positions, mass); }

SpringGridModel build_spring_grid_model(const Volume<uint8_t>& occupancy, const SpringGridMaterial& material,
                                        const Volume<float>* fraction) {
  occupancy.geometry.validate("occupancy");
  require_range(material.density, 0, true, "density");
  require_range(material.face_stiffness, 0, true, "face_stiffness");
  require_range(material.edge_stiffness, 0, false, "edge_stiffness");
  require_range(material.face_damping, 0, false, "face_damping");
  require_range(material.edge_damping, 0, false, "edge_damping");
  if (material.mass_from_fraction) {
    if (fraction == nullptr) throw InputError("occupancy", "fraction", "mass_from_fraction needs the fraction volume");
    if (!fraction->geometry.same_lattice(occupancy.geometry))
      throw InputError("occupancy", "fraction", "is not on the occupancy lattice");
  }

  SpringGridModel model;
  model.lattice = occupancy.geometry;
  const auto& dims = occupancy.geometry.dims;
  for (int64_t flat = 0; flat < occupancy.geometry.voxel_count(); ++flat)
    if (occupancy.voxels[static_cast<std::size_t>(flat)] != 0) model.cells.push_back(flat);
  if (model.cells.empty()) throw InputError("occupancy", "/grid/occupancy", "no occupied cell: nothing to simulate");
  if (model.cells.size() > static_cast<std::size_t>(std::numeric_limits<int32_t>::max()))
    throw InputError("occupancy", "/grid/occupancy", "more than 2^31 - 1 particles");
  const auto n = static_cast<int64_t>(model.cells.size());
  check_allocation(static_cast<uint64_t>(n), kGridDirections * 4 + 4 + 16, "occupancy", "particles");
  check_allocation(static_cast<uint64_t>(occupancy.geometry.voxel_count()), 4, "occupancy", "cell map");

  // Dense cell -> particle map, built once and dropped.
  std::vector<int32_t> particle_of_cell(static_cast<std::size_t>(occupancy.geometry.voxel_count()), -1);
  for (int64_t p = 0; p < n; ++p) particle_of_cell[static_cast<std::size_t>(model.cells[p])] = static_cast<int32_t>(p);

  const Eigen::Matrix3d m = occupancy.geometry.index_to_world_matrix();
  for (int d = 0; d < kGridDirections; ++d) {
    const auto& o = kGridDirectionOffsets[d];
    model.rest_length[d] = static_cast<Real>((m * Eigen::Vector3d(o[0], o[1], o[2])).norm());
    model.stiffness[d] = static_cast<Real>(is_face_direction(d) ? material.face_stiffness : material.edge_stiffness);
    model.damping[d] = static_cast<Real>(is_face_direction(d) ? material.face_damping : material.edge_damping);
  }

  model.neighbours.assign(static_cast<std::size_t>(kGridDirections * n), -1);
  model.spring_mask.assign(static_cast<std::size_t>(n), 0u);
  model.rest_positions.resize(static_cast<std::size_t>(3 * n));
  model.mass.resize(static_cast<std::size_t>(n));
  const double cell_volume = occupancy.geometry.voxel_volume_mm3();
  for (int64_t p = 0; p < n; ++p) {
    const int64_t flat = model.cells[p];
    const int64_t i = flat % dims[0], j = (flat / dims[0]) % dims[1], k = flat / (dims[0] * dims[1]);
    const Eigen::Vector3d c = occupancy.geometry.index_to_world(Eigen::Vector3d(i, j, k));
    for (int a = 0; a < 3; ++a) model.rest_positions[3 * p + a] = static_cast<Real>(c[a]);
    const double f = material.mass_from_fraction ? std::clamp<double>(fraction->voxels[flat], 0.0, 1.0) : 1.0;
    // A cell whose fraction rounds to 0 still carries a small mass so that 1/m stays finite.
    model.mass[p] = static_cast<Real>(material.density * cell_volume * std::max(f, 1e-3));
    uint32_t mask = 0;
    for (int d = 0; d < kGridDirections; ++d) {
      const auto& o = kGridDirectionOffsets[d];
      const int64_t a = i + o[0], b = j + o[1], c2 = k + o[2];
      if (a < 0 || b < 0 || c2 < 0 || a >= dims[0] || b >= dims[1] || c2 >= dims[2]) continue;
      const int32_t q = particle_of_cell[static_cast<std::size_t>(occupancy.geometry.flat_index(a, b, c2))];
      if (q < 0) continue;
      model.neighbours[static_cast<std::size_t>(d * n + p)] = q;
      if (model.stiffness[d] > 0 || model.damping[d] > 0) mask |= 1u << d;
    }
    model.spring_mask[p] = mask;
  }
  const int64_t chunks = (n + kGridChunk - 1) / kGridChunk;
  model.chunk_offsets.assign(static_cast<std::size_t>(chunks * kGridDirections), kIrregularChunk);
  for (int64_t c = 0; c < chunks; ++c)
    for (int d = 0; d < kGridDirections; ++d) {
      const int64_t i0 = c * kGridChunk;
      if (i0 + kGridChunk > n) continue;  // the last partial chunk runs the per-particle kernel
      int64_t lo = INT64_MAX, hi = INT64_MIN;
      for (int64_t i = i0; i < i0 + kGridChunk; ++i) {
        const int32_t q = model.neighbours[static_cast<std::size_t>(d * n + i)];
        if (q >= 0) lo = std::min<int64_t>(lo, q - i), hi = std::max<int64_t>(hi, q - i);
      }
      if (lo > hi) lo = hi = 0;  // no neighbour in this direction: the particles read themselves
      if (lo == hi && i0 + lo >= 0 && i0 + lo + kGridChunk <= n)
        model.chunk_offsets[static_cast<std::size_t>(c * kGridDirections + d)] = static_cast<int32_t>(lo);
    }
  return model;
}

SpringGridModel build_spring_grid_model(const OccupancyGrid& grid, const SpringGridMaterial& material) {
  return build_spring_grid_model(grid.occupancy, material, grid.fraction.voxels.empty() ? nullptr : &grid.fraction);
}

bool cut_grid_spring(SpringGridModel& model, int32_t particle, int direction) {
  if (particle < 0 || particle >= model.particle_count() || direction < 0 || direction >= kGridDirections)
    throw InputError("cut", "spring", "particle " + std::to_string(particle) + " direction " + std::to_string(direction) +
                                          " out of range");
  const int64_t n = model.particle_count();
  const int32_t other = model.neighbours[static_cast<std::size_t>(direction * n + particle)];
  const uint32_t bit = 1u << direction;
  if (other < 0 || (model.spring_mask[particle] & bit) == 0) return false;
  model.spring_mask[particle] &= ~bit;
  model.spring_mask[other] &= ~(1u << opposite_direction(direction));
  return true;
}

std::vector<int32_t> particles_with_label(const SpringGridModel& model, const Volume<uint16_t>& label, uint16_t value) {
  if (!label.geometry.same_lattice(model.lattice))
    throw InputError("fixed region", "label", "the label volume is not on the grid model's lattice");
  std::vector<int32_t> ids;
  for (int32_t p = 0; p < model.particle_count(); ++p)
    if (label.voxels[static_cast<std::size_t>(model.cells[p])] == value) ids.push_back(p);
  return ids;
}

}  // namespace ctsurg::sim
