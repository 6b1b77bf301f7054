// Spring stiffness from a Young's modulus, so that a spring-mass model and an FEM model of the same
// tissue can be compared fairly (issue 9) and a scenario can name a material instead of a stiffness.
//
// Grid (18 neighbours, cubic cells of side h). With face springs k1 (length h) and edge springs k2
// (length h sqrt 2), the strain energy density of a uniform strain e is, summing
// k l^2 (n.e.n)^2 / 2 over a cell's 3 face and 6 edge springs and dividing by h^3,
//   C11 = (k1 + 2 k2) / h,  C12 = C44 = k2 / h   (cubic elastic constants).
// Isotropy (C11 - C12 = 2 C44) needs k1 = k2 = k; then lambda = mu = k / h: Poisson's ratio 0.25 (the
// Cauchy relation of central pair forces) and E = mu (3 lambda + 2 mu) / (lambda + mu) = 2.5 k / h, so
//   k = 0.4 E h.
// The lattice reproduces E exactly in the bulk at nu = 0.25; it cannot represent another nu (a tissue
// with nu 0.45 is stiffer in compression of volume than the lattice). Non-cubic cells use h = the cube
// root of the cell volume. tests/sim/test_spring_calibration.cpp measures the effective modulus of a
// stretched block.
//
// Tet mesh edges (explicit springs): k_ij = E sum_{tets t containing edge ij} V_t / l_ij^2. For an
// isotropic distribution of edge directions (<n_x^4> = 1/5) and 6 edges per tet, the uniaxial-strain
// energy density is E e^2 6/5 / 2 = (lambda + 2 mu) e^2 / 2 at nu = 0.25: the same calibration in the
// mean (an edge network is isotropic only on average; the error is measured in the test).
//
// Units: E in Pa (= g/(mm s^2)), lengths mm, stiffness g/s^2, mass g.
#pragma once

#include "ctsurg/core/image_geometry.h"
#include "ctsurg/core/tet_mesh_file.h"
#include "ctsurg/sim/base/material_presets.h"
#include "ctsurg/sim/springs/explicit_spring_model.h"
#include "ctsurg/sim/springs/spring_grid_model.h"

#include <vector>

namespace ctsurg::sim {

// k = 0.4 E h, g/s^2, h = cbrt(cell volume of `lattice`) mm.
double grid_spring_stiffness(double youngs_modulus_pa, const ImageGeometry& lattice);
// A grid material with both spring classes at grid_spring_stiffness and the material's density.
SpringGridMaterial calibrated_grid_material(const Material& material, const ImageGeometry& lattice,
                                            bool mass_from_fraction = false);
// The tet mesh's edges as springs with k_ij = E sum V_t / l_ij^2 and masses lumped from the tets
// (density * V_t / 4 per node), built by explicit_model_from_tet_mesh. Throws InputError("material", ...)
// for a material out of range and InputError("tetmesh", ...) for an empty mesh or a node in no tet of
// positive volume.
ExplicitSpringModel calibrated_tet_spring_model(const TetMesh& mesh, const Material& material);

// Each organ its own material (a scenario's material.labels and material.inclusions on a spring model):
// `materials` indexed by element. Materials are validated; InputError("material", ...) names the first
// bad one, InputError("materials", ...) an index out of range or a vector of the wrong size.
//
// Tets: tet t of materials[tet_material[t]] lumps its density * V_t / 4 onto each node, and edge ij
// gets k_ij = sum_t E_t V_t / l_ij^2 over its tets (the calibration above, tet by tet).
ExplicitSpringModel calibrated_tet_spring_model(const TetMesh& mesh, const std::vector<Material>& materials,
                                                const std::vector<int32_t>& tet_material);
// A grid's springs as an explicit model (explicit_model_from_grid) with particle p of
// materials[particle_material[p]]: its mass grid.mass[p] * density / grid_density (grid_density: the
// density the grid model was built with, g/mm^3), and the spring between cells a and b two half-springs
// in series, one in each cell: k = grid_spring_stiffness(2 E_a E_b / (E_a + E_b)), which is k = 0.4 E h
// inside one tissue and the series stiffness across an interface. Damping stays the grid's.
ExplicitSpringModel calibrated_grid_spring_model(const SpringGridModel& grid, const std::vector<Material>& materials,
                                                 const std::vector<int32_t>& particle_material, double grid_density);

}  // namespace ctsurg::sim
