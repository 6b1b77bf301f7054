#include "ctsurg/sim/fem/fem_model.h"

#include "ctsurg/sim/fem/kernels/fem_element_impl.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/tet_mesh_file.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>
#include <string>

namespace ctsurg::sim {
namespace {

constexpr const char* kWhere = "fem model";

std::string tet_text(const std::vector<double>& nodes, const int32_t* t) {
  std::ostringstream s;
  s << "corners";
  for (int a = 0; a < 4; ++a)
    s << " " << t[a] << " (" << nodes[3 * t[a]] << ", " << nodes[3 * t[a] + 1] << ", " << nodes[3 * t[a] + 2] << ")";
  return s.str();
}

}  // namespace

FemModel build_fem_model(const std::vector<double>& nodes, const std::vector<int32_t>& tets, const FemMaterial& material) {
  validate_fem_material(material, kWhere);
  if (nodes.size() % 3 != 0) throw InputError(kWhere, "nodes", "expected #N x 3 coordinates, got " + std::to_string(nodes.size()) + " values");
  if (tets.size() % 4 != 0) throw InputError(kWhere, "tets", "expected #T x 4 node ids, got " + std::to_string(tets.size()) + " values");
  if (tets.empty()) throw InputError(kWhere, "tets", "the mesh has no tetrahedra");
  // The kernels index corner forces as 12 e + 3 a in int32 (fem_forces_impl.h): at most INT32_MAX / 12
  // tets (178 million).
  if (nodes.size() / 3 > static_cast<std::size_t>(INT32_MAX / 4) || tets.size() / 4 > static_cast<std::size_t>(INT32_MAX / 12))
    throw InputError(kWhere, "tets", "mesh too large: at most " + std::to_string(INT32_MAX / 12) + " tets and " +
                                         std::to_string(INT32_MAX / 4) + " nodes (32-bit corner indices)");
  for (std::size_t i = 0; i < nodes.size(); ++i)
    if (!std::isfinite(nodes[i])) throw InputError(kWhere, "nodes", "node " + std::to_string(i / 3) + " is not finite");

  FemModel m;
  m.material = material;
  m.lame = lame_parameters(material);
  m.nodes = nodes;
  m.tets = tets;
  const int32_t n = m.node_count(), t_count = m.tet_count();
  for (int32_t e = 0; e < t_count; ++e)
    for (int a = 0; a < 4; ++a) {
      const int32_t v = tets[4 * e + a];
      if (v < 0 || v >= n)
        throw InputError(kWhere, "tets", "tet " + std::to_string(e) + " corner " + std::to_string(a) + ": node id " +
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
      throw InputError(kWhere, "tets", "tet " + std::to_string(e) + " is inverted or flat (signed volume " +
                                           std::to_string(volume) + " mm^3, must be > 0; " + tet_text(nodes, t) + ")");
    if (volume < 1e-9 * longest * longest * longest)
      throw InputError(kWhere, "tets", "tet " + std::to_string(e) + " is degenerate (volume " + std::to_string(volume) +
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
      m.node_mass[v] += material.density * m.rest_volume[e] / 4;
    }
  for (int32_t i = 0; i < n; ++i)
    if (m.node_offsets[i + 1] == m.node_offsets[i]) ++m.unused_nodes;
  return m;
}

FemModel build_fem_model(const TetMesh& mesh, const FemMaterial& material) {
  return build_fem_model(mesh.nodes, mesh.tets, material);
}

double fem_total_volume(const FemModel& model) {
  return std::accumulate(model.rest_volume.begin(), model.rest_volume.end(), 0.0);
}

double fem_total_mass(const FemModel& model) {
  return std::accumulate(model.node_mass.begin(), model.node_mass.end(), 0.0);
}

}  // namespace ctsurg::sim
