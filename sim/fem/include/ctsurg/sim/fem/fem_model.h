// The tetrahedral finite element model (total Lagrangian): the rest mesh, its materials (one, or one per
// element group: each organ of a patient's mesh its own, by tet label), and what every
// solver precomputes once per element and node (Huang et al., the FEM paper, section 3: linear
// interpolation in each tet), for linear (4-node) or quadratic (10-node) tets.
//
//   per element: rest volume V = det(Dm) / 6 and B = Dm^-1, Dm = [X1-X0, X2-X0, X3-X0] (columns) of its
//                corners, whose rows are the corners' barycentric gradients (fem_element_impl.h; the
//                quadratic tet's edges are straight, so B and V are its corners' too:
//                fem_quadratic_element_impl.h)
//   per node:    lumped mass (linear: m_i = sum over the tets at i of rho_e V / 4 (rho_e: the tet's material's), the paper's diagonal
//                mass matrix, section 3.3; quadratic: the HRZ diagonal scaling of the consistent mass,
//                rho V / 36 per corner and 4 rho V / 27 per edge node, positive where row sums are not),
//                the consistent load of a unit body acceleration (integral of rho N_i: the static
//                solver's gravity; linear: the mass; quadratic: -rho V / 20 per corner, rho V / 5 per edge
//                node), and the CSR list of (element, node slot) at the node, sorted by element: every
//                per-node sum is a gather over it, deterministic, no atomics
//
// Units: nodes mm, volumes mm^3, B 1/mm, masses g.
#pragma once

#include "ctsurg/sim/fem/fem_material.h"

#include <array>
#include <cstdint>
#include <vector>

namespace ctsurg {
struct TetMesh;
}

namespace ctsurg::sim {

struct FemModel {
  // The materials: element e has materials[element_material[e]], or materials[0] for every element when
  // element_material is empty (one material). 1 .. kFemMaxMaterials, each validated.
  std::vector<FemMaterial> materials;
  std::vector<LameParameters> lame;           // #M: each material's mu and lambda
  std::vector<int32_t> element_material;      // #T indices into materials, or empty
  std::vector<double> nodes;         // #N x 3 rest positions, mm (LPS minus frame_origin), row-major
  int32_t order = 1;                 // 1: linear tets (4 nodes), 2: quadratic (10 nodes; fem_quadratic_element_impl.h)
  std::vector<int32_t> tets;         // #T x nodes_per_element() node ids, corners positively oriented
  std::vector<double> rest_volume;   // #T mm^3 (> 0)
  std::vector<double> dm_inverse;    // #T x 9, Dm^-1 row-major, 1/mm
  std::vector<double> node_mass;     // #N g, lumped; 0 for a node that no tet uses
  std::vector<double> node_load;     // #N g: the consistent load of a unit acceleration (see above)
  int32_t vertex_count = 0;          // the linear mesh's nodes (ids below it); a quadratic model's edge nodes follow
  std::vector<int32_t> node_offsets; // #N + 1, CSR row starts into node_corners
  std::vector<int32_t> node_corners; // #T x npe entries npe e + slot (npe = nodes_per_element()), each row sorted
  int32_t unused_nodes = 0;          // nodes no tet uses (held fixed by every solver)
  // Where the nodes' frame sits in LPS mm: a scenario runs in a local frame near its model (LPS minus
  // this), and messages that name a point add it back. {0, 0, 0} when nodes are LPS.
  std::array<double, 3> frame_origin{0, 0, 0};

  int32_t node_count() const { return static_cast<int32_t>(nodes.size() / 3); }
  int32_t material_index(int32_t e) const { return element_material.empty() ? 0 : element_material[static_cast<std::size_t>(e)]; }
  const FemMaterial& material_of(int32_t e) const { return materials[static_cast<std::size_t>(material_index(e))]; }
  const LameParameters& lame_of(int32_t e) const { return lame[static_cast<std::size_t>(material_index(e))]; }
  // Whether every material has this law (e.g. linear: the stiffness does not depend on u).
  bool every_law(FemLaw law) const;
  // Whether some material's exact tangent may be indefinite (laws/fem_law_types.h).
  bool any_indefinite_tangent() const;
  int32_t nodes_per_element() const { return order == 2 ? 10 : 4; }
  int32_t tet_count() const { return static_cast<int32_t>(tets.size() / static_cast<std::size_t>(nodes_per_element())); }
};

// Builds the model from nodes (#N x 3, LPS mm) and tets (#T x 4, node ids). Throws
// InputError("fem model", field, ...) for: a material out of range (validate_fem_material), more than
// kFemMaxMaterials materials or an element_material (#T, or empty for materials[0] everywhere) that
// is not #T ids of them ("materials"), sizes that are not multiples of 3 and 4, no tets, a non-finite node ("nodes"), a node id out of range, an
// inverted tet (signed volume <= 0: "tet 17 is inverted ...") or a degenerate one (|V| below 1e-9 of
// its longest edge cubed: "tet 17 is degenerate ...") ("tets"), all before anything is solved.
FemModel build_fem_model(const std::vector<double>& nodes, const std::vector<int32_t>& tets, const std::vector<FemMaterial>& materials,
                         const std::vector<int32_t>& element_material);
FemModel build_fem_model(const std::vector<double>& nodes, const std::vector<int32_t>& tets, const FemMaterial& material);
// The same from a ctsurg tet mesh (mesh.nodes, mesh.tets; labels are not used: one material).
FemModel build_fem_model(const TetMesh& mesh, const FemMaterial& material);
// The quadratic model of the same linear tets: their nodes first (ids kept), then one node at the middle
// of every edge, numbered in the order the edges are first met (tet by tet, edges in slot order 4..9):
// deterministic. Same errors as build_fem_model.
FemModel build_quadratic_fem_model(const std::vector<double>& nodes, const std::vector<int32_t>& tets,
                                   const std::vector<FemMaterial>& materials, const std::vector<int32_t>& element_material);
FemModel build_quadratic_fem_model(const std::vector<double>& nodes, const std::vector<int32_t>& tets, const FemMaterial& material);
FemModel build_quadratic_fem_model(const TetMesh& mesh, const FemMaterial& material);
// The same model with every material's law linear (the same E, nu, density; constants dropped): the
// local region's linear model (its small-strain stiffness is each law's at rest).
FemModel fem_linearised(FemModel model);
// The edge node of a quadratic model between vertices i and j (either order), or -1.
int32_t fem_edge_node(const FemModel& model, int32_t i, int32_t j);

// A point of the nodes' frame (mm) in LPS mm, for messages: p + model.frame_origin.
inline std::array<double, 3> fem_lps_point(const FemModel& model, const double* p) {
  return {p[0] + model.frame_origin[0], p[1] + model.frame_origin[1], p[2] + model.frame_origin[2]};
}

// Total rest volume, mm^3, and total mass, g.
double fem_total_volume(const FemModel& model);
double fem_total_mass(const FemModel& model);

}  // namespace ctsurg::sim
