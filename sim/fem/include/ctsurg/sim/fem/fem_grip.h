// A volume grip: a tool that holds the material inside its sphere, not the nodes that happen to lie
// there (issue 32). The grip is a penalty integrated over the elements:
//
//   E_grip(u) = 1/2 integral over the rest body of k w(X) |u(X) - s g(X)|^2 dV
//             = 1/2 (u - s g)^T P (u - s g),      P_ab = k integral of w N_a N_b dV  (x I_3)
//
// with u(X) = sum N_a u_a the FE displacement, g(X) = u_captured(X) + (c - c_captured) the captured
// material moved rigidly with the tool's centre c, s the solver's load factor, and w the tool's
// weight: 1 inside the sphere (at the capture: the material whose position then, X + u_captured(X), is
// inside), 0 outside, a smoothstep over a band of width `edge` centred on the radius (so that the load
// is a smooth function of where the nodes are: a node that crosses the sphere's surface changes P
// continuously, where a node set jumps). k is a stiffness per volume (uN/mm per mm^3): the scenario sets
// it as a multiple of E / r^2 (the tissue's stiffness at the tool's size), so the material inside
// follows the tool to about 1/ratio of the tissue's own deformation there.
//
// Because the load is an integral over the material, it converges as the mesh is refined (P is the
// weighted mass matrix of the region: tests/sim/fem/test_fem_grip.cpp measures the reaction force and
// the field at three mesh sizes), where a held node set changes with every mesh. The integral: each
// element the band crosses is split (8 children by its edge midpoints, recursively, until a piece's
// bounding radius is half the band's width), each piece integrated by a collapsed (Duffy) Gauss-Legendre
// product rule: 4^3 points, exact for the P2 mass integrand (degree 4), where w is 1; 2^3 in the band
// (the sphere's weighted volume within 0.2 % on every mesh tested; an 8 mm grip on 6 mm cells costs
// 32 ms on linear tets, 62 ms on quadratic: bench_fem's BM_FemGripCapture).
//
// The force the tool exerts on the tissue is f = -P (u - s g) (per node); its total and its moment about
// the tool's centre are the tool's reaction (fem_grip_load; the tissue pulls the tool with the opposite).
//
// Units: mm, uN (k uN/mm^4, P uN/mm); arrays #N x 3 row-major.
#pragma once

#include "ctsurg/sim/fem/fem_model.h"

#include <array>
#include <cstdint>
#include <vector>

namespace ctsurg::sim {

struct FemGrip {
  std::vector<int32_t> elements;        // #G elements the grip covers (increasing)
  std::vector<int32_t> nodes;           // #H nodes of those elements (increasing)
  std::vector<int32_t> element_nodes;   // #G x npe: each element's nodes as indices into `nodes`
  std::vector<double> matrices;         // #G x npe x npe: k integral of w N_a N_b over the element, uN/mm (symmetric)
  std::vector<double> captured;         // #H x 3 mm: the nodes' displacement at the capture
  std::vector<double> target;           // #H x 3 mm: g at the nodes at load factor 1
  double volume_mm3 = 0;                // integral of w over the body (the material the grip holds), mm^3
};

// The grip of a sphere (centre, radius mm; edge mm: the band's width, (0, radius]) on the material at
// displacement u (#N x 3 mm, the capture), with stiffness k (uN/mm^4, > 0). Its target is u_captured
// (fem_grip_move moves it). An empty grip (no material inside) has no elements. Throws InputError("fem
// grip", field, ...) for a radius, edge or stiffness out of range or u not #N x 3.
FemGrip fem_capture_grip(const FemModel& model, const std::vector<double>& u, const std::array<double, 3>& centre, double radius,
                         double edge, double stiffness);
// The target of a captured grip moved by `travel` (mm) from its capture: g_a = u_captured_a + travel.
void fem_grip_move(FemGrip& grip, const std::array<double, 3>& travel);

// f -= P (u - s g) (the grip's forces added to f, #N x 3 uN). Serial, element order: deterministic.
void fem_grip_add_forces(const FemModel& model, const FemGrip& grip, const double* u, double s, double* f);
// 1/2 (u - s g)^T P (u - s g), nJ.
double fem_grip_energy(const FemModel& model, const FemGrip& grip, const double* u, double s);
// out += P v (#N x 3).
void fem_grip_add_product(const FemModel& model, const FemGrip& grip, const double* v, double* out);

// The total of nodal forces f (#N x 3 uN) over `nodes` (N) and its moment about `about` (N mm), each
// force at its node's position X + u (#N x 3 mm): a tool's load from the forces it applies.
std::array<double, 6> fem_nodal_load(const FemModel& model, const std::vector<int32_t>& nodes, const std::vector<double>& u,
                                     const std::vector<double>& f, const std::array<double, 3>& about);

// The load the grip exerts on the tissue at u (load factor 1): the total force (N) and its moment
// about `about` (N mm), from the nodal forces -P (u - g) at the nodes' positions X + u (LPS axes).
std::array<double, 6> fem_grip_load(const FemModel& model, const FemGrip& grip, const std::vector<double>& u,
                                    const std::array<double, 3>& about);

}  // namespace ctsurg::sim
