#include "ctsurg/sim/fem/fem_model.h"

#include "ctsurg/sim/fem/kernels/fem_element_impl.h"
#include "ctsurg/sim/fem/kernels/fem_quadratic_element_impl.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/tet_mesh_file.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <numeric>
#include <sstream>
#include <string>

namespace ctsurg::sim {
namespace {

constexpr const char* kModelWhere = "fem model";

std::string tet_text(const std::vector<double>& nodes, const int32_t* t) {
  std::ostringstream s;
  s << "corners";
  for (int a = 0; a < 4; ++a)
    s << " " << t[a] << " (" << nodes[3 * t[a]] << ", " << nodes[3 * t[a] + 1] << ", " << nodes[3 * t[a] + 2] << ")";
  return s.str();
}

}  // namespace

FemModel build_fem_model(const std::vector<double>& nodes, const std::vector<int32_t>& tets, const FemMaterial& material) {
  return build_fem_model(nodes, tets, std::vector<FemMaterial>{material}, {});
}

FemModel build_fem_model(const std::vector<double>& nodes, const std::vector<int32_t>& tets, const std::vector<FemMaterial>& materials,
                         const std::vector<int32_t>& element_material) {
  if (materials.empty() || materials.size() > static_cast<std::size_t>(kFemMaxMaterials))
    throw InputError(kModelWhere, "materials", "a model has 1 to " + std::to_string(kFemMaxMaterials) + " materials, got " + std::to_string(materials.size()));
  for (std::size_t k = 0; k < materials.size(); ++k) {
    const std::string where = materials.size() == 1 ? std::string(kModelWhere) : std::string(kModelWhere) + " material " + std::to_string(k);
    validate_fem_material(materials[k], where.c_str());
  }
  if (nodes.size() % 3 != 0) throw InputError(kModelWhere, "nodes", "expected #N x 3 coordinates, got " + std::to_string(nodes.size()) + " values");
  if (tets.size() % 4 != 0) throw InputError(kModelWhere, "tets", "expected #T x 4 node ids, got " + std::to_string(tets.size()) + " values");
  if (tets.empty()) throw InputError(kModelWhere, "tets", "the mesh has no tetrahedra");
  // The kernels index corner forces as 12 e + 3 a in int32 (fem_forces_impl.h): at most INT32_MAX / 12
  // tets (178 million).
  if (nodes.size() / 3 > static_cast<std::size_t>(INT32_MAX / 4) || tets.size() / 4 > static_cast<std::size_t>(INT32_MAX / 12))
    throw InputError(kModelWhere, "tets", "mesh too large: at most " + std::to_string(INT32_MAX / 12) + " tets and " +
                                         std::to_string(INT32_MAX / 4) + " nodes (32-bit corner indices)");
  for (std::size_t i = 0; i < nodes.size(); ++i)
    if (!std::isfinite(nodes[i])) throw InputError(kModelWhere, "nodes", "node " + std::to_string(i / 3) + " is not finite");

  FemModel m;
  m.materials = materials;
  for (const FemMaterial& material : materials) m.lame.push_back(lame_parameters(material));
  m.nodes = nodes;
  m.tets = tets;
  const int32_t n = m.node_count(), t_count = m.tet_count();
  if (!element_material.empty()) {
    if (element_material.size() != static_cast<std::size_t>(t_count))
      throw InputError(kModelWhere, "materials", "expected one material id per tet (" + std::to_string(t_count) + "), got " + std::to_string(element_material.size()));
    for (int32_t e = 0; e < t_count; ++e)
      if (element_material[static_cast<std::size_t>(e)] < 0 || element_material[static_cast<std::size_t>(e)] >= static_cast<int32_t>(materials.size()))
        throw InputError(kModelWhere, "materials", "tet " + std::to_string(e) + " has material id " + std::to_string(element_material[static_cast<std::size_t>(e)]) +
                                                  ", not one of the " + std::to_string(materials.size()) + " materials");
    m.element_material = element_material;
  }
  for (int32_t e = 0; e < t_count; ++e)
    for (int a = 0; a < 4; ++a) {
      const int32_t v = tets[4 * e + a];
      if (v < 0 || v >= n)
        throw InputError(kModelWhere, "tets", "tet " + std::to_string(e) + " corner " + std::to_string(a) + ": node id " +
                                             std::to_string(v) + " out of range [0, " + std::to_string(n) + ")");
    }

  m.rest_volume.resize(t_count);
  m.dm_inverse.resize(9 * static_cast<std::size_t>(t_count));
  for (int32_t e = 0; e < t_count; ++e) {
    const int32_t* t = &tets[4 * e];
    double dm[9];
    double longest = 0;
    for (int k = 0; k < 3; ++k)
      for (int r = 0; r < 3; ++r) dm[r * 3 + k] = nodes[3 * t[k + 1] + r] - nodes[3 * t[0] + r];
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) {
        double l2 = 0;
        for (int r = 0; r < 3; ++r) l2 += std::pow(nodes[3 * t[a] + r] - nodes[3 * t[b] + r], 2);
        longest = std::max(longest, std::sqrt(l2));
      }
    const double det = det3(dm);
    const double volume = det / 6;
    if (!(volume > 0))
      throw InputError(kModelWhere, "tets", "tet " + std::to_string(e) + " is inverted or flat (signed volume " +
                                           std::to_string(volume) + " mm^3, must be > 0; " + tet_text(nodes, t) + ")");
    if (volume < 1e-9 * longest * longest * longest)
      throw InputError(kModelWhere, "tets", "tet " + std::to_string(e) + " is degenerate (volume " + std::to_string(volume) +
                                           " mm^3 for a longest edge of " + std::to_string(longest) + " mm; " +
                                           tet_text(nodes, t) + ")");
    double c[9];
    cofactor3(dm, c);  // Dm^-1 = cof(Dm)^T / det
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) m.dm_inverse[9 * e + r * 3 + k] = c[k * 3 + r] / det;
    m.rest_volume[e] = volume;
  }

  // Lumped masses (summed per node in element order: deterministic) and the node -> corner CSR.
  m.node_mass.assign(n, 0.0);
  m.node_offsets.assign(n + 1, 0);
  for (int32_t v : tets) ++m.node_offsets[v + 1];
  std::partial_sum(m.node_offsets.begin(), m.node_offsets.end(), m.node_offsets.begin());
  m.node_corners.resize(tets.size());
  std::vector<int32_t> fill(m.node_offsets.begin(), m.node_offsets.end() - 1);
  for (int32_t e = 0; e < t_count; ++e)
    for (int a = 0; a < 4; ++a) {
      const int32_t v = tets[4 * e + a];
      m.node_corners[fill[v]++] = 4 * e + a;  // e increases: rows come out sorted
      m.node_mass[v] += m.material_of(e).density * m.rest_volume[e] / 4;
    }
  for (int32_t i = 0; i < n; ++i)
    if (m.node_offsets[i + 1] == m.node_offsets[i]) ++m.unused_nodes;
  m.node_load = m.node_mass;
  m.vertex_count = n;
  return m;
}

FemModel build_fem_model(const TetMesh& mesh, const FemMaterial& material) {
  return build_fem_model(mesh.nodes, mesh.tets, material);
}

FemModel build_quadratic_fem_model(const std::vector<double>& nodes, const std::vector<int32_t>& tets, const FemMaterial& material) {
  return build_quadratic_fem_model(nodes, tets, std::vector<FemMaterial>{material}, {});
}

FemModel build_quadratic_fem_model(const std::vector<double>& nodes, const std::vector<int32_t>& tets,
                                   const std::vector<FemMaterial>& materials, const std::vector<int32_t>& element_material) {
  FemModel m = build_fem_model(nodes, tets, materials, element_material);  // checks, volumes, B of the corners
  const int32_t n1 = m.node_count(), t_count = m.tet_count();
  // Slot forces are indexed 30 e + 3 a in int32 (fem_forces_impl.h).
  if (t_count > INT32_MAX / 30) throw InputError(kModelWhere, "tets", "mesh too large for quadratic tets: at most " + std::to_string(INT32_MAX / 30) + " tets");
  // Edge nodes, numbered as first met; each vertex's edges to higher vertices in a small sorted list.
  std::vector<std::vector<std::pair<int32_t, int32_t>>> edges_of(static_cast<std::size_t>(n1));
  std::vector<int32_t> tets10(10 * static_cast<std::size_t>(t_count));
  int32_t next = n1;
  for (int32_t e = 0; e < t_count; ++e) {
    const int32_t* t = &tets[4 * static_cast<std::size_t>(e)];
    for (int a = 0; a < 4; ++a) tets10[10 * static_cast<std::size_t>(e) + a] = t[a];
    for (int k = 0; k < 6; ++k) {
      int i, j;
      fem_quadratic_edge(k, i, j);
      const int32_t lo = std::min(t[i], t[j]), hi = std::max(t[i], t[j]);
      auto& list = edges_of[static_cast<std::size_t>(lo)];
      auto it = std::lower_bound(list.begin(), list.end(), std::make_pair(hi, INT32_MIN));
      if (it == list.end() || it->first != hi) {
        if (next == INT32_MAX / 4) throw InputError(kModelWhere, "tets", "mesh too large for quadratic tets (32-bit node ids)");
        it = list.insert(it, {hi, next++});
      }
      tets10[10 * static_cast<std::size_t>(e) + 4 + k] = it->second;
    }
  }
  m.nodes.resize(3 * static_cast<std::size_t>(next));
  for (int32_t lo = 0; lo < n1; ++lo)
    for (const auto& [hi, id] : edges_of[static_cast<std::size_t>(lo)])
      for (int c = 0; c < 3; ++c) m.nodes[3 * static_cast<std::size_t>(id) + c] = 0.5 * (nodes[3 * lo + c] + nodes[3 * hi + c]);
  m.order = 2;
  m.tets = std::move(tets10);
  // Masses, loads and the node -> slot CSR over the 10 slots.
  const int32_t n = next;
  m.node_mass.assign(n, 0.0);
  m.node_load.assign(n, 0.0);
  m.node_offsets.assign(n + 1, 0);
  for (int32_t v : m.tets) ++m.node_offsets[v + 1];
  std::partial_sum(m.node_offsets.begin(), m.node_offsets.end(), m.node_offsets.begin());
  m.node_corners.resize(m.tets.size());
  std::vector<int32_t> fill(m.node_offsets.begin(), m.node_offsets.end() - 1);
  for (int32_t e = 0; e < t_count; ++e) {
    const double rv = m.material_of(e).density * m.rest_volume[e];
    for (int a = 0; a < 10; ++a) {
      const int32_t v = m.tets[10 * static_cast<std::size_t>(e) + a];
      m.node_corners[fill[v]++] = 10 * e + a;
      m.node_mass[v] += a < 4 ? rv / 36 : rv * 4 / 27;
      m.node_load[v] += a < 4 ? -rv / 20 : rv / 5;
    }
  }
  m.unused_nodes = 0;
  for (int32_t i = 0; i < n; ++i)
    if (m.node_offsets[i + 1] == m.node_offsets[i]) ++m.unused_nodes;
  return m;
}

FemModel build_quadratic_fem_model(const TetMesh& mesh, const FemMaterial& material) {
  return build_quadratic_fem_model(mesh.nodes, mesh.tets, material);
}

int32_t fem_edge_node(const FemModel& model, int32_t i, int32_t j) {
  if (model.order != 2 || i < 0 || j < 0 || i >= model.vertex_count || j >= model.vertex_count || i == j) return -1;
  for (int32_t k = model.node_offsets[i]; k < model.node_offsets[i + 1]; ++k) {
    const int32_t e = model.node_corners[k] / 10;
    const int32_t* t = &model.tets[10 * static_cast<std::size_t>(e)];
    for (int s = 0; s < 6; ++s) {
      int a, b;
      fem_quadratic_edge(s, a, b);
      if ((t[a] == i && t[b] == j) || (t[a] == j && t[b] == i)) return t[4 + s];
    }
  }
  return -1;
}

double fem_total_volume(const FemModel& model) {
  return std::accumulate(model.rest_volume.begin(), model.rest_volume.end(), 0.0);
}

bool FemModel::every_law(FemLaw law) const {
  return std::all_of(materials.begin(), materials.end(), [law](const FemMaterial& m) { return m.law == law; });
}

bool FemModel::any_indefinite_tangent() const {
  return std::any_of(materials.begin(), materials.end(), [](const FemMaterial& m) { return fem_law_traits(m.law).indefinite_tangent; });
}

FemModel fem_linearised(FemModel model) {
  for (FemMaterial& m : model.materials) {
    m.law = FemLaw::linear;
    m.constants = {};
  }
  return model;
}

double fem_total_mass(const FemModel& model) {
  return std::accumulate(model.node_mass.begin(), model.node_mass.end(), 0.0);
}

}  // namespace ctsurg::sim
