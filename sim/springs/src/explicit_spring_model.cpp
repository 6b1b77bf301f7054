#include "ctsurg/sim/springs/explicit_spring_model.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/memory_guard.h"
#include "ctsurg/core/tet_mesh_file.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <string>
#include <utility>

namespace ctsurg::sim {

int64_t ExplicitSpringModel::alive_spring_count() const {
  return std::count(alive.begin(), alive.end(), uint8_t{1});
}

ExplicitSpringView ExplicitSpringModel::view() const {
  const bool ell = !chunk_start.empty();
  return {row_offsets.data(),
          row_neighbour.data(),
          row_spring.data(),
          stiffness.data(),
          rest_length.data(),
          damping.data(),
          alive.data(),
          particle_count(),
          ell ? chunk_start.data() : nullptr,
          ell ? ell_neighbour.data() : nullptr,
          ell ? ell_stiffness.data() : nullptr,
          ell ? ell_rest_length.data() : nullptr,
          ell ? ell_damping.data() : nullptr,
          ell ? ell_present.data() : nullptr};
}

namespace {

// The sliced ELLPACK layout of the rows (see the header).
void build_chunk_layout(ExplicitSpringModel& m) {
  const int64_t n = m.particle_count(), chunks = n / kExplicitChunk;
  m.chunk_start.assign(static_cast<std::size_t>(chunks + 1), 0);
  for (int64_t c = 0; c < chunks; ++c) {
    int32_t width = 0;
    for (int64_t i = c * kExplicitChunk; i < (c + 1) * kExplicitChunk; ++i)
      width = std::max(width, m.row_offsets[i + 1] - m.row_offsets[i]);
    m.chunk_start[c + 1] = m.chunk_start[c] + int64_t{width} * kExplicitChunk;
  }
  const auto size = static_cast<std::size_t>(m.chunk_start[chunks]);
  check_allocation(size, 20, "springs", "chunk layout");
  m.ell_neighbour.resize(size), m.ell_stiffness.assign(size, 0), m.ell_rest_length.assign(size, 0);
  m.ell_damping.assign(size, 0), m.ell_present.assign(size, 0);
  m.spring_entries.assign(2 * static_cast<std::size_t>(m.spring_count()), -1);
  for (int64_t c = 0; c < chunks; ++c) {
    const int64_t width = (m.chunk_start[c + 1] - m.chunk_start[c]) / kExplicitChunk;
    for (int64_t k = 0; k < kExplicitChunk; ++k) {
      const int64_t i = c * kExplicitChunk + k;
      for (int64_t e = 0; e < width; ++e) {
        const auto at = static_cast<std::size_t>(m.chunk_start[c] + e * kExplicitChunk + k);
        const int64_t row = m.row_offsets[i] + e;
        if (row >= m.row_offsets[i + 1]) {
          m.ell_neighbour[at] = static_cast<int32_t>(i);  // padding: the particle itself, present 0
          continue;
        }
        const int32_t s = m.row_spring[row];
        m.ell_neighbour[at] = m.row_neighbour[row];
        m.ell_stiffness[at] = m.stiffness[s], m.ell_rest_length[at] = m.rest_length[s], m.ell_damping[at] = m.damping[s];
        m.ell_present[at] = m.alive[s] ? Real(1) : Real(0);
        m.spring_entries[2 * s + (m.spring_entries[2 * s] < 0 ? 0 : 1)] = static_cast<int64_t>(at);
      }
    }
  }
}

}  // namespace

void sync_cut_springs(ExplicitSpringModel& model) {
  for (int32_t s = 0; s < model.spring_count(); ++s) {
    if (model.alive[s]) continue;
    for (int end = 0; end < 2; ++end) {
      const int64_t at = model.spring_entries.empty() ? -1 : model.spring_entries[2 * static_cast<std::size_t>(s) + end];
      if (at >= 0) model.ell_present[static_cast<std::size_t>(at)] = 0;
    }
  }
}

ParticleState ExplicitSpringModel::make_state() const { return ParticleState(rest_positions, mass); }

ExplicitSpringModel build_explicit_spring_model(const std::vector<Real>& rest_positions, const std::vector<Real>& mass,
                                                const std::vector<Spring>& springs) {
  if (rest_positions.size() != 3 * mass.size())
    throw InputError("particles", "rest_positions", "expected 3 x " + std::to_string(mass.size()) + " values");
  if (mass.empty()) throw InputError("particles", "mass", "no particle");
  if (mass.size() > static_cast<std::size_t>(std::numeric_limits<int32_t>::max()) ||
      springs.size() > static_cast<std::size_t>(std::numeric_limits<int32_t>::max() / 2))
    throw InputError("springs", "count", "more than 2^31 - 1 particles or 2^30 - 1 springs");
  for (std::size_t p = 0; p < mass.size(); ++p)
    if (!(std::isfinite(mass[p]) && mass[p] > 0))
      throw InputError("particles", "mass", "particle " + std::to_string(p) + ": must be finite and > 0");
  const auto n = static_cast<int32_t>(mass.size());
  const auto ns = static_cast<int32_t>(springs.size());
  check_allocation(static_cast<uint64_t>(ns), 2 * 8 + 16, "springs", "adjacency");

  ExplicitSpringModel model;
  model.rest_positions = rest_positions;
  model.mass = mass;
  model.spring_ends.resize(2 * static_cast<std::size_t>(ns));
  model.stiffness.resize(ns), model.rest_length.resize(ns), model.damping.resize(ns);
  model.alive.assign(ns, 1);
  std::vector<int32_t> degree(static_cast<std::size_t>(n) + 1, 0);
  for (int32_t s = 0; s < ns; ++s) {
    const Spring& sp = springs[s];
    const auto bad = [&](const std::string& what) {
      throw InputError("springs", "spring " + std::to_string(s), what);
    };
    if (sp.i < 0 || sp.j < 0 || sp.i >= n || sp.j >= n) bad("particle id out of range [0, " + std::to_string(n) + ")");
    if (sp.i == sp.j) bad("connects particle " + std::to_string(sp.i) + " to itself");
    if (!(std::isfinite(sp.stiffness) && sp.stiffness >= 0)) bad("stiffness must be finite and >= 0");
    if (!(std::isfinite(sp.rest_length) && sp.rest_length >= 0)) bad("rest length must be finite and >= 0");
    if (!(std::isfinite(sp.damping) && sp.damping >= 0)) bad("damping must be finite and >= 0");
    model.spring_ends[2 * s] = sp.i, model.spring_ends[2 * s + 1] = sp.j;
    model.stiffness[s] = static_cast<Real>(sp.stiffness);
    model.rest_length[s] = static_cast<Real>(sp.rest_length);
    model.damping[s] = static_cast<Real>(sp.damping);
    model.spring_damping = model.spring_damping || sp.damping > 0;
    ++degree[sp.i + 1], ++degree[sp.j + 1];
  }
  model.row_offsets.resize(static_cast<std::size_t>(n) + 1);
  std::partial_sum(degree.begin(), degree.end(), model.row_offsets.begin());
  model.row_neighbour.resize(2 * static_cast<std::size_t>(ns));
  model.row_spring.resize(2 * static_cast<std::size_t>(ns));
  std::vector<int32_t> fill(model.row_offsets.begin(), model.row_offsets.end() - 1);
  for (int32_t s = 0; s < ns; ++s) {
    const int32_t a = springs[s].i, b = springs[s].j;
    model.row_neighbour[fill[a]] = b, model.row_spring[fill[a]++] = s;
    model.row_neighbour[fill[b]] = a, model.row_spring[fill[b]++] = s;
  }
  // Rows in (neighbour, spring) order: memory order of the gathered positions, independent of the
  // order the springs were listed in.
  std::vector<std::pair<int32_t, int32_t>> row;
  for (int32_t p = 0; p < n; ++p) {
    row.clear();
    for (int32_t e = model.row_offsets[p]; e < model.row_offsets[p + 1]; ++e)
      row.emplace_back(model.row_neighbour[e], model.row_spring[e]);
    std::sort(row.begin(), row.end());
    for (std::size_t q = 0; q < row.size(); ++q) {
      model.row_neighbour[model.row_offsets[p] + q] = row[q].first;
      model.row_spring[model.row_offsets[p] + q] = row[q].second;
    }
  }
  build_chunk_layout(model);
  return model;
}

ExplicitSpringModel explicit_model_from_grid(const SpringGridModel& grid) {
  const int64_t n = grid.particle_count();
  std::vector<Spring> springs;
  springs.reserve(static_cast<std::size_t>(grid.spring_count()));
  for (int64_t a = 0; a < n; ++a)
    for (int d = 0; d < kGridDirections; ++d) {
      if ((grid.spring_mask[a] >> d & 1u) == 0) continue;
      const int32_t b = grid.neighbours[static_cast<std::size_t>(d * n + a)];
      if (b <= a) continue;
      springs.push_back({static_cast<int32_t>(a), b, grid.stiffness[d], grid.rest_length[d], grid.damping[d]});
    }
  return build_explicit_spring_model(grid.rest_positions, grid.mass, springs);
}

ExplicitSpringModel explicit_model_from_tet_mesh(const TetMesh& mesh, double density, double stiffness, double damping) {
  return explicit_model_from_tet_mesh(mesh, density, [stiffness](double, double) { return stiffness; }, damping);
}

ExplicitSpringModel explicit_model_from_tet_mesh(const TetMesh& mesh, double density,
                                                 const std::function<double(double, double)>& stiffness, double damping) {
  if (!(std::isfinite(density) && density > 0)) throw InputError("tetmesh", "density", "must be finite and > 0");
  const std::size_t tets = static_cast<std::size_t>(std::max<int64_t>(mesh.tet_count(), 0));
  return explicit_model_from_tet_mesh(mesh, std::vector<double>(tets, density), std::vector<double>(tets, 1.0), stiffness, damping);
}

ExplicitSpringModel explicit_model_from_tet_mesh(const TetMesh& mesh, const std::vector<double>& tet_density,
                                                 const std::vector<double>& tet_weight,
                                                 const std::function<double(double, double)>& stiffness, double damping) {
  if (mesh.node_count() == 0 || mesh.tet_count() == 0) throw InputError("tetmesh", "/tetmesh/tets", "empty mesh");
  if (tet_density.size() != static_cast<std::size_t>(mesh.tet_count()) || tet_weight.size() != tet_density.size()) {
    throw InputError("tetmesh", "materials", "one density and one weight per tet: " + std::to_string(tet_density.size()) + " and " +
                                                 std::to_string(tet_weight.size()) + " for " + std::to_string(mesh.tet_count()) + " tets");
  }
  for (std::size_t t = 0; t < tet_density.size(); ++t) {
    if (!(std::isfinite(tet_density[t]) && tet_density[t] > 0)) throw InputError("tetmesh", "density", "tet " + std::to_string(t) + ": must be finite and > 0");
    if (!(std::isfinite(tet_weight[t]) && tet_weight[t] >= 0)) throw InputError("tetmesh", "weight", "tet " + std::to_string(t) + ": must be finite and >= 0");
  }
  const int64_t n = mesh.node_count();
  std::vector<double> lumped(static_cast<std::size_t>(n), 0.0);
  std::map<std::pair<int32_t, int32_t>, double> edges;  // -> weighted volume of its tets; ordered: deterministic spring order
  for (int64_t t = 0; t < mesh.tet_count(); ++t) {
    const int32_t* v = &mesh.tets[static_cast<std::size_t>(4 * t)];
    for (int a = 0; a < 4; ++a)
      if (v[a] < 0 || v[a] >= n) throw InputError("tetmesh", "/tetmesh/tets", "tet " + std::to_string(t) + " names a missing node");
    Eigen::Vector3d p[4];
    for (int a = 0; a < 4; ++a) p[a] = Eigen::Vector3d(&mesh.nodes[static_cast<std::size_t>(3 * v[a])]);
    const double volume = std::abs((p[1] - p[0]).dot((p[2] - p[0]).cross(p[3] - p[0]))) / 6.0;
    const double weighted = tet_weight[static_cast<std::size_t>(t)] * volume;
    for (int a = 0; a < 4; ++a) {
      lumped[v[a]] += tet_density[static_cast<std::size_t>(t)] * volume / 4.0;
      for (int b = a + 1; b < 4; ++b) edges[std::minmax(v[a], v[b])] += weighted;
    }
  }
  std::vector<Real> rest(static_cast<std::size_t>(3 * n)), mass(static_cast<std::size_t>(n));
  for (int64_t i = 0; i < n; ++i) {
    if (!(lumped[i] > 0)) throw InputError("tetmesh", "/tetmesh/nodes", "node " + std::to_string(i) + " is in no tet of positive volume");
    mass[i] = static_cast<Real>(lumped[i]);
    for (int a = 0; a < 3; ++a) rest[3 * i + a] = static_cast<Real>(mesh.nodes[3 * i + a]);
  }
  std::vector<Spring> springs;
  springs.reserve(edges.size());
  for (const auto& [e, volume] : edges) {
    const Eigen::Vector3d a(&mesh.nodes[static_cast<std::size_t>(3 * e.first)]), b(&mesh.nodes[static_cast<std::size_t>(3 * e.second)]);
    const double length = (a - b).norm();
    springs.push_back({e.first, e.second, stiffness(volume, length), length, damping});
  }
  return build_explicit_spring_model(rest, mass, springs);
}

bool cut_explicit_spring(ExplicitSpringModel& model, int32_t s) {
  if (s < 0 || s >= model.spring_count()) throw InputError("cut", "spring", std::to_string(s) + " out of range");
  const bool was = model.alive[s] != 0;
  model.alive[s] = 0;
  for (int end = 0; end < 2 && !model.spring_entries.empty(); ++end) {
    const int64_t at = model.spring_entries[2 * static_cast<std::size_t>(s) + end];
    if (at >= 0) model.ell_present[static_cast<std::size_t>(at)] = 0;
  }
  return was;
}

}  // namespace ctsurg::sim
