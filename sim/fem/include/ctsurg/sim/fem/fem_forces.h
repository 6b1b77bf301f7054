// Internal (elastic) forces, strain energy and element tangent stiffness of a FemModel at a
// displacement field, in double precision: the building blocks of the static solver
// (fem_static_solver.h) and the references of the explicit dynamics (fem_explicit_dynamics.h).
//
// The nodal force is f_i = -dE/du_i, E = sum_e V_e psi(F_e) (the paper's R(a) of eq. 1 with the
// opposite sign: R = -f). Element forces are computed per element, then summed per node through the
// model's node -> (element, corner) CSR (gather, deterministic for any thread count). Quadratic models
// integrate by 4-point quadrature (fem_quadratic_element_impl.h).
//
// Units: displacements #N x 3 mm (row-major), forces #N x 3 uN (= g mm/s^2), energy nJ, stiffness uN/mm.
#pragma once

#include "ctsurg/sim/fem/fem_model.h"

#include <array>
#include <cstdint>
#include <vector>

namespace ctsurg::sim {

// Internal forces `forces` (#N x 3, uN; resized) at `displacements` (#N x 3, mm). Returns the lowest id
// of an inverted element (det F <= 0; its forces are taken as zero, never NaN), or -1. threads: 0 = auto.
// Throws InputError("fem forces", "displacements", ...) on a size mismatch.
int32_t fem_internal_forces(const FemModel& model, const std::vector<double>& displacements, std::vector<double>& forces,
                            int threads = 0);

// Strain energy sum_e V_e psi(F_e) (quadratic: over the quadrature points), nJ; +infinity if a
// Neo-Hookean element is inverted (quadratic: neo-Hookean or corotational).
double fem_strain_energy(const FemModel& model, const std::vector<double>& displacements);

// Linear tets only (InputError(..., "order", ...) for a quadratic model, whose F varies inside a tet):
// Deformation gradient of tet `e` (3x3 row-major) and its first Piola-Kirchhoff stress (Pa).
std::array<double, 9> fem_deformation_gradient(const FemModel& model, int32_t e, const std::vector<double>& displacements);
std::array<double, 9> fem_element_stress(const FemModel& model, int32_t e, const std::vector<double>& displacements);

// Tangent stiffness of tet `e` (12 x 12 row-major, uN/mm; rows and columns corner-major, xyz),
// K = d^2 E_e / du^2; all zero for an inverted element.
std::array<double, 144> fem_element_stiffness(const FemModel& model, int32_t e, const std::vector<double>& displacements);

}  // namespace ctsurg::sim
