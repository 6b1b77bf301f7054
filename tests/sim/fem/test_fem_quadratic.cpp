// Tests of the quadratic (10-node) tetrahedra (fem_model.h build_quadratic_fem_model,
// kernels/fem_quadratic_element_impl.h, and the static solver on them): the model (edge nodes, masses,
// loads), forces against the energy and the tangent against the forces, the P2 patch test (a quadratic
// field reproduced exactly, where linear tets cannot), the cantilever against Timoshenko, and the
// convergence orders of linear and quadratic tets on a smooth exact solution.
#include "ctsurg/core/error.h"
#include "ctsurg/sim/fem/fem_box_mesh.h"
#include "ctsurg/sim/fem/fem_explicit_dynamics.h"
#include "ctsurg/sim/fem/fem_forces.h"
#include "ctsurg/sim/fem/fem_implicit_dynamics.h"
#include "ctsurg/sim/fem/fem_model.h"
#include "ctsurg/sim/fem/fem_static_solver.h"
#include "ctsurg/sim/fem/kernels/fem_quadratic_element_impl.h"
#include "fem_test_models.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <numeric>
#include <string>

namespace ctsurg::sim {
namespace {

using test::fem_material;

FemModel quadratic_box(FemLaw law, std::array<int, 3> cells, std::array<double, 3> size, double nu = 0.3) {
  const auto box = fem_box_mesh(cells, size);
  return build_quadratic_fem_model(box.nodes, box.tets, fem_material(law, 3e4, nu));
}

using Field = std::function<std::array<double, 3>(const double*)>;

// Every node on the box's boundary held at `exact`; the interior solved (static); returns the largest
// and the RMS nodal error over the interior nodes.
std::pair<double, double> boundary_value_error(const FemModel& m, const std::array<double, 3>& size, const Field& exact) {
  FemBoundaryConditions bc;
  for (int32_t i = 0; i < m.node_count(); ++i) {
    bool on = false;
    for (int c = 0; c < 3; ++c) on = on || std::abs(m.nodes[3 * i + c]) < 1e-9 || std::abs(m.nodes[3 * i + c] - size[c]) < 1e-9;
    if (!on) continue;
    bc.prescribed_nodes.push_back(i);
    const auto u = exact(&m.nodes[3 * i]);
    bc.prescribed_displacements.insert(bc.prescribed_displacements.end(), u.begin(), u.end());
  }
  FemStaticOptions o;
  o.cg_tolerance = 1e-13;
  const auto r = solve_fem_static(m, bc, {}, o);
  double worst = 0, sum = 0;
  std::vector<uint8_t> held(static_cast<std::size_t>(m.node_count()), 0);
  for (const int32_t i : bc.prescribed_nodes) held[static_cast<std::size_t>(i)] = 1;
  int64_t interior = 0;
  for (int32_t i = 0; i < m.node_count(); ++i) {
    if (held[static_cast<std::size_t>(i)]) continue;
    ++interior;
    const auto u = exact(&m.nodes[3 * i]);
    for (int c = 0; c < 3; ++c) {
      const double d = r.displacements[3 * i + c] - u[c];
      worst = std::max(worst, std::abs(d));
      sum += d * d;
    }
  }
  return {worst, std::sqrt(sum / (3.0 * static_cast<double>(interior)))};
}

// A box of Kuhn tets with its interior vertices moved by up to `fraction` of a cell (deterministic):
// an irregular mesh, on which no nodal superconvergence of the uniform one hides the error.
FemBoxMesh irregular_box(std::array<int, 3> cells, std::array<double, 3> size, double fraction) {
  auto box = fem_box_mesh(cells, size);
  const int32_t n = static_cast<int32_t>(box.nodes.size() / 3);
  for (int32_t i = 0; i < n; ++i) {
    bool on = false;
    for (int c = 0; c < 3; ++c) on = on || std::abs(box.nodes[3 * i + c]) < 1e-12 || std::abs(box.nodes[3 * i + c] - size[c]) < 1e-12;
    if (on) continue;
    for (int c = 0; c < 3; ++c) box.nodes[3 * i + c] += fraction * size[c] / cells[c] * std::sin(3.1 * i + 1.7 * c);
  }
  return box;
}

TEST(FemQuadratic, ModelHasOneNodePerEdgeAndItsMassesAndLoadsSumToTheMass) {
  const auto box = fem_box_mesh({2, 1, 1}, {4, 2, 2});
  const FemModel lin = build_fem_model(box.nodes, box.tets, fem_material(FemLaw::neo_hookean));
  const FemModel m = build_quadratic_fem_model(box.nodes, box.tets, fem_material(FemLaw::neo_hookean));
  EXPECT_EQ(m.order, 2);
  EXPECT_EQ(m.nodes_per_element(), 10);
  EXPECT_EQ(m.tet_count(), lin.tet_count());
  EXPECT_EQ(m.vertex_count, lin.node_count());
  // Edges of the Kuhn mesh of 2 x 1 x 1 cubes: V - E + F - T = 1 with F = (4 T + boundary faces) / 2.
  const int64_t boundary_faces = 2 * (2 * 1 + 2 * 1 + 1 * 1) * 2;
  const int64_t faces = (4 * lin.tet_count() + boundary_faces) / 2;
  const int64_t edges = lin.node_count() + faces - lin.tet_count() - 1;
  EXPECT_EQ(m.node_count(), lin.node_count() + edges);
  const double total = fem_total_mass(lin);
  EXPECT_NEAR(std::accumulate(m.node_mass.begin(), m.node_mass.end(), 0.0), total, 1e-12 * total);
  EXPECT_NEAR(std::accumulate(m.node_load.begin(), m.node_load.end(), 0.0), total, 1e-12 * total);
  for (int32_t i = 0; i < m.node_count(); ++i) EXPECT_GT(m.node_mass[i], 0);
  // Edge nodes sit at the middle of their edge, and are found from it.
  for (int32_t e = 0; e < m.tet_count(); ++e)
    for (int k = 0; k < 6; ++k) {
      int a, b;
      fem_quadratic_edge(k, a, b);
      const int32_t* t = &m.tets[10 * e];
      for (int c = 0; c < 3; ++c) EXPECT_DOUBLE_EQ(m.nodes[3 * t[4 + k] + c], 0.5 * (m.nodes[3 * t[a] + c] + m.nodes[3 * t[b] + c]));
      EXPECT_EQ(fem_edge_node(m, t[b], t[a]), t[4 + k]);
    }
  EXPECT_EQ(fem_edge_node(m, 0, 0), -1);
  EXPECT_EQ(fem_edge_node(lin, 0, 1), -1);
}

TEST(FemQuadratic, ShapeFunctionsInterpolateTheirNodes) {
  for (int node = 0; node < 10; ++node) {
    double l[4] = {0, 0, 0, 0};
    if (node < 4) {
      l[node] = 1;
    } else {
      int a, b;
      fem_quadratic_edge(node - 4, a, b);
      l[a] = l[b] = 0.5;
    }
    double N[10];
    fem_quadratic_shape(l, N);
    for (int k = 0; k < 10; ++k) EXPECT_NEAR(N[k], k == node ? 1.0 : 0.0, 1e-15);
  }
}

TEST(FemQuadratic, ForcesAreMinusTheEnergyGradientAndTheTangentTheirDerivative) {
  for (auto law : {FemLaw::linear, FemLaw::stvk, FemLaw::neo_hookean}) {
    const FemModel m = quadratic_box(law, {1, 1, 1}, {2, 2, 2});
    std::vector<double> u(m.nodes.size());
    for (std::size_t k = 0; k < u.size(); ++k) u[k] = 0.15 * std::sin(1.3 * k + 0.4);
    std::vector<double> f;
    ASSERT_EQ(fem_internal_forces(m, u, f), -1);
    const double h = 1e-6;
    double worst = 0, scale = 0;
    for (std::size_t k = 0; k < u.size(); k += 7) {
      auto up = u, um = u;
      up[k] += h;
      um[k] -= h;
      const double g = (fem_strain_energy(m, up) - fem_strain_energy(m, um)) / (2 * h);
      worst = std::max(worst, std::abs(-g - f[k]));
      scale = std::max(scale, std::abs(f[k]));
    }
    EXPECT_LT(worst, 1e-5 * scale) << fem_law_name(law);
  }
}

TEST(FemQuadratic, PatchTestAQuadraticFieldIsReproducedExactly) {
  // u = e (x^2 - y^2, -2 x y, 0): divergence-free and harmonic, so in equilibrium for the linear law
  // with no body force. It lies in the quadratic tets' space: the solution is exact at every node.
  // Linear tets cannot represent it (their error is what the quadratic ones remove).
  const std::array<double, 3> size{3, 3, 3};
  const double eps = 1e-3;
  const Field exact = [&](const double* x) { return std::array<double, 3>{eps * (x[0] * x[0] - x[1] * x[1]), -2 * eps * x[0] * x[1], 0.0}; };
  const auto box = irregular_box({3, 3, 3}, size, 0.2);
  const auto p2 = boundary_value_error(build_quadratic_fem_model(box.nodes, box.tets, fem_material(FemLaw::linear)), size, exact);
  const auto p1 = boundary_value_error(build_fem_model(box.nodes, box.tets, fem_material(FemLaw::linear)), size, exact);
  std::printf("quadratic field: largest nodal error %.3g mm with quadratic tets, %.3g mm with linear ones (field up to %.3g mm)\n",
              p2.first, p1.first, eps * 9);
  EXPECT_LT(p2.first, 1e-12);
  EXPECT_GT(p1.first, 1e-5);
}

TEST(FemQuadratic, ConvergenceOrdersOnASmoothExactSolution) {
  // u = e (exp(x) cos y, -exp(x) sin y, 0) / (harmonic and divergence-free: equilibrium for the linear
  // law), boundary held at it, on irregular meshes of the unit cube (linear tets 4, 8, 16 cells a
  // side; quadratic 2, 4, 8). RMS nodal error ~ h^p between the two finest.
  const std::array<double, 3> size{1, 1, 1};
  const double eps = 1e-3;
  const Field exact = [&](const double* x) {
    return std::array<double, 3>{eps * std::exp(x[0]) * std::cos(x[1]), -eps * std::exp(x[0]) * std::sin(x[1]), 0.0};
  };
  double order[2] = {0, 0};
  for (int quadratic = 0; quadratic < 2; ++quadratic) {
    std::vector<double> err;
    for (int n : quadratic ? std::vector<int>{2, 4, 8} : std::vector<int>{4, 8, 16}) {
      const auto box = irregular_box({n, n, n}, size, 0.15);
      const FemModel m = quadratic ? build_quadratic_fem_model(box.nodes, box.tets, fem_material(FemLaw::linear))
                                   : build_fem_model(box.nodes, box.tets, fem_material(FemLaw::linear));
      err.push_back(boundary_value_error(m, size, exact).second);
    }
    order[quadratic] = std::log2(err[1] / err[2]);
    std::printf("%s tets: RMS nodal error %.3g, %.3g, %.3g (of a field up to %.3g) at h = 1/%d, 1/%d, 1/%d: order %.2f\n",
                quadratic ? "quadratic" : "linear", err[0], err[1], err[2], eps * std::exp(1.0), quadratic ? 2 : 4, quadratic ? 4 : 8,
                quadratic ? 8 : 16, order[quadratic]);
  }
  EXPECT_GT(order[0], 1.7);
  EXPECT_LT(order[0], 2.5);
  EXPECT_GT(order[1], 2.5);  // 3 asymptotically; 2.7 between 1/4 and 1/8 on these irregular meshes
  EXPECT_GT(order[1], order[0] + 0.5);
}

TEST(FemQuadratic, CantileverIsWithinHalfAPercentOfTimoshenko) {
  // 40 x 4 x 4 mm, clamped at x = 0, a tip shear of 1 mN spread over the x = 40 face (consistent loads
  // of a uniform traction on 6-node triangles: 1/3 of each triangle's share at its edge nodes).
  const double L = 40, b = 4, E = 3e4, nu = 0.3, P = 1000;  // mm, Pa, uN
  for (int quadratic = 0; quadratic < 2; ++quadratic) {
    const int nc = 2;
    const auto box = fem_box_mesh({10 * nc, nc, nc}, {L, b, b});
    const FemModel m = quadratic ? build_quadratic_fem_model(box.nodes, box.tets, fem_material(FemLaw::linear, E, nu))
                                 : build_fem_model(box.nodes, box.tets, fem_material(FemLaw::linear, E, nu));
    // Beam theory's clamp: the root section stays plane (u_x = 0 over it), its middle lines do not move
    // sideways, and it is free to contract (Poisson): held components only (a full clamp stiffens the
    // root by 0.8 % here).
    FemBoundaryConditions bc;
    for (const int32_t i : test::nodes_where(m, 0, 0.0)) {
      bc.fixed_components.push_back(3 * i);
      if (std::abs(m.nodes[3 * i + 2] - b / 2) < 1e-9) bc.fixed_components.push_back(3 * i + 2);
      if (std::abs(m.nodes[3 * i + 1] - b / 2) < 1e-9) bc.fixed_components.push_back(3 * i + 1);
    }
    FemLoads loads;
    loads.forces.assign(m.nodes.size(), 0.0);
    const auto tip = test::nodes_where(m, 0, L);
    // Uniform traction on the end face, consistent nodal loads per boundary triangle: area / 3 at each
    // corner (linear) or at each edge node (quadratic; the corners get none).
    static const int faces[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
    const int npe = m.nodes_per_element();
    for (int32_t e = 0; e < m.tet_count(); ++e)
      for (const auto& fc : faces) {
        const int32_t* t = &m.tets[static_cast<std::size_t>(npe) * e];
        bool on = true;
        for (int k = 0; k < 3; ++k) on = on && std::abs(m.nodes[3 * t[fc[k]]] - L) < 1e-9;
        if (!on) continue;
        const double area = 0.5 * (b / nc) * (b / nc), share = -P * (area / (b * b)) / 3;  // Kuhn faces: half a 2 x 2 mm square
        for (int k = 0; k < 3; ++k) {
          if (!quadratic) {
            loads.forces[3 * t[fc[k]] + 2] += share;
            continue;
          }
          const int32_t mid = fem_edge_node(m, t[fc[k]], t[fc[(k + 1) % 3]]);
          loads.forces[3 * mid + 2] += share;
        }
      }
    FemStaticOptions o;
    o.cg_tolerance = 1e-13;
    const auto r = solve_fem_static(m, bc, loads, o);
    double tip_w = 0;
    for (const int32_t i : tip) tip_w += r.displacements[3 * i + 2] / static_cast<double>(tip.size());
    const double I = b * b * b * b / 12, A = b * b, G = E / (2 * (1 + nu)), kappa = 10 * (1 + nu) / (12 + 11 * nu);
    const double timoshenko = -(P * L * L * L / (3 * E * I) + P * L / (kappa * G * A));
    const double rel = tip_w / timoshenko - 1;
    std::printf("cantilever 20 x 2 x 2 cells, %s tets: tip %.4f mm, Timoshenko %.4f mm (%+.2f %%)\n", quadratic ? "quadratic" : "linear",
                tip_w, timoshenko, 100 * rel);
    if (quadratic) EXPECT_LT(std::abs(rel), 0.005);
    else EXPECT_GT(std::abs(rel), 0.05);  // linear tets lock in bending at this mesh
  }
}

TEST(FemQuadratic, NeoHookeanGrabAndImplicitDynamicsSettleTogether) {
  const FemModel m = quadratic_box(FemLaw::neo_hookean, {6, 2, 2}, {12, 4, 4});
  FemBoundaryConditions bc;
  bc.fixed_nodes = test::nodes_where(m, 0, 0.0);
  const auto tip = test::nodes_where(m, 0, 12.0);
  bc.prescribed_nodes = tip;
  for (std::size_t g = 0; g < tip.size(); ++g) bc.prescribed_displacements.insert(bc.prescribed_displacements.end(), {0.0, 0.0, 3.0});
  FemStaticOptions so;
  so.tolerance_mm = 1e-8;
  const auto stat = solve_fem_static(m, bc, {}, so);
  EXPECT_TRUE(stat.report.converged);
  EXPECT_TRUE(stat.report.direct);
  FemImplicitOptions o;
  o.newton.tolerance_mm = 1e-8;
  FemImplicitDynamics d(m, o);
  d.set_supports(bc.fixed_nodes);
  d.set_prescribed(tip, bc.prescribed_displacements);
  d.step(90);
  double worst = 0;
  for (std::size_t k = 0; k < stat.displacements.size(); ++k) worst = std::max(worst, std::abs(stat.displacements[k] - d.displacements()[k]));
  EXPECT_LT(worst, 1e-5);
  EXPECT_THROW(fem_critical_time_step(m, 0.5), InputError);  // the explicit dynamics runs linear tets only
  EXPECT_THROW(fem_element_stiffness(m, 0, stat.displacements), InputError);
}

}  // namespace
}  // namespace ctsurg::sim
