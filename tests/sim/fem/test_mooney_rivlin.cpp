// Tests of sim/fem/laws/mooney_rivlin.h (the general law properties are test_fem_material.cpp's, for
// every law): the closed forms that only a correct c01 term meets, Neo-Hookean as its c01 = 0 case, the
// checks of its constants, and a static solve on a block.
#include "ctsurg/sim/fem/laws/mooney_rivlin.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/fem/fem_material.h"
#include "ctsurg/sim/fem/fem_static_solver.h"
#include "fem_test_models.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ctsurg::sim {
namespace {

using M9 = std::array<double, 9>;

FemLawParameters<double> mooney(double c10, double c01, double nu) {
  return fem_law_parameters(fem_material_from_constants(FemLaw::mooney_rivlin, {c10, c01}, nu, 1.06e-3));
}

// Simple shear F = I + g e1 (x) e2 (J = 1): a Mooney-Rivlin solid's shear stress is exactly
// sigma_12 = 2 (c10 + c01) g at every g (Ogden, Non-linear elastic deformations, 1984, section 5.3), and
// its normal stress differences split the constants: sigma_11 - sigma_33 = 2 c10 g^2,
// sigma_22 - sigma_33 = -2 c01 g^2 (from sigma = 2 c10 B + 2 c01 (I1 B - B^2) - m I, B = F F^T).
TEST(MooneyRivlin, SimpleShearClosedForms) {
  const double c10 = 3000, c01 = 800;
  const auto k = mooney(c10, c01, 0.45);
  for (const double g : {0.01, 0.3, 1.0}) {
    const M9 F{1, g, 0, 0, 1, 0, 0, 0, 1};
    M9 P;
    ASSERT_TRUE(first_piola_kirchhoff(k, F, P));
    M9 sigma{};  // Cauchy stress P F^T (J = 1)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        for (int q = 0; q < 3; ++q) sigma[r * 3 + c] += P[r * 3 + q] * F[c * 3 + q];
    EXPECT_NEAR(sigma[1], 2 * (c10 + c01) * g, 1e-9 * c10) << "g " << g;
    EXPECT_NEAR(sigma[3], sigma[1], 1e-9 * c10);
    EXPECT_NEAR(sigma[0] - sigma[8], 2 * c10 * g * g, 1e-9 * c10) << "g " << g;
    EXPECT_NEAR(sigma[4] - sigma[8], -2 * c01 * g * g, 1e-9 * c10) << "g " << g;
  }
}

// c01 = 0 is the compressible Neo-Hookean law with mu = 2 c10 (the same lambda).
TEST(MooneyRivlin, WithoutC01ItIsNeoHookean) {
  const double c10 = 5000, nu = 0.4;
  const auto k = mooney(c10, 0, nu);
  EXPECT_DOUBLE_EQ(k.mu, 2 * c10);
  const FemLawParameters<double> nh{FemLaw::neo_hookean, k.mu, k.lambda, {0, 0}};
  const M9 F{1.3, 0.2, -0.1, 0.05, 0.8, 0.1, 0.0, -0.2, 1.1};
  M9 a, b;
  ASSERT_TRUE(first_piola_kirchhoff(k, F, a));
  ASSERT_TRUE(first_piola_kirchhoff(nh, F, b));
  for (int i = 0; i < 9; ++i) EXPECT_NEAR(a[i], b[i], 1e-10 * c10);
  EXPECT_NEAR(strain_energy_density(k, F), strain_energy_density(nh, F), 1e-10 * c10);
}

// Under uniaxial stretch the c01 term softens the response relative to Neo-Hookean of the same
// small-strain shear modulus (the Mooney plot's slope): at 30 % stretch, lateral sides free, P11 of
// Mooney-Rivlin lies below Neo-Hookean's. The lateral stretch is found by bisection on P22 = 0.
TEST(MooneyRivlin, SofterThanNeoHookeanInUniaxialTension) {
  const double nu = 0.45;
  const auto mr = mooney(2000, 2000, nu);
  const FemLawParameters<double> nh{FemLaw::neo_hookean, mr.mu, mr.lambda, {0, 0}};
  const auto p11 = [](const FemLawParameters<double>& k, double a) {
    double lo = 0.5, hi = 1.0;
    M9 P;
    for (int it = 0; it < 200; ++it) {
      const double b = 0.5 * (lo + hi);
      first_piola_kirchhoff(k, M9{a, 0, 0, 0, b, 0, 0, 0, b}, P);
      (P[4] > 0 ? hi : lo) = b;
    }
    first_piola_kirchhoff(k, M9{a, 0, 0, 0, lo, 0, 0, 0, lo}, P);
    return P[0];
  };
  const double small = 1.0005;
  EXPECT_NEAR(p11(mr, small), p11(nh, small), 1e-3 * std::abs(p11(nh, small)));  // same Young's modulus
  EXPECT_LT(p11(mr, 1.3), 0.97 * p11(nh, 1.3));
}

TEST(MooneyRivlin, ConstantsAreCheckedNamingTheField) {
  const auto field_of = [](const FemMaterial& m) {
    try {
      validate_fem_material(m, "liver.yaml");
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), "liver.yaml");
      return e.field();
    }
    return std::string("accepted");
  };
  FemMaterial m = fem_material_from_constants(FemLaw::mooney_rivlin, {3000, 500}, 0.45, 1.06e-3);
  EXPECT_EQ(field_of(m), "accepted");
  EXPECT_NEAR(m.youngs_modulus, 4 * 3500 * 1.45, 1e-9);
  FemMaterial bad = m;
  bad.constants[1] = -1;
  EXPECT_EQ(field_of(bad), "c01_pa");
  bad = m;
  bad.constants[0] = NAN;
  EXPECT_EQ(field_of(bad), "c10_pa");
  bad = m;
  bad.youngs_modulus *= 2;  // E is the constants', not free
  EXPECT_EQ(field_of(bad), "youngs_modulus");
  // lambda - 4 c01 <= 0: a low Poisson's ratio with a large c01.
  EXPECT_THROW(fem_material_from_constants(FemLaw::mooney_rivlin, {100, 3000}, 0.05, 1.06e-3), InputError);
  bad = m;
  bad.constants = {0, 0};
  bad.youngs_modulus = 1;
  EXPECT_EQ(field_of(bad), "c10_pa");
  // A law without constants carries none.
  FemMaterial nh;
  nh.law = FemLaw::neo_hookean;
  nh.constants[0] = 1;
  EXPECT_EQ(field_of(nh), "constants");
}

// A block held at one end and pulled at the other by prescribed nodes converges with Newton; with
// c01 = 0 it gives Neo-Hookean's displacements, with c01 > 0 (same small-strain E) different ones.
TEST(MooneyRivlin, StaticSolveOnABlock) {
  const auto box = fem_box_mesh({6, 2, 2}, {12, 4, 4});
  const auto solve = [&](const FemMaterial& material) {
    const FemModel model = build_fem_model(box.nodes, box.tets, material);
    FemBoundaryConditions bc;
    for (int32_t i = 0; i < model.node_count(); ++i) {
      const double x = model.nodes[3 * static_cast<size_t>(i)];
      if (x < 1e-9) bc.fixed_nodes.push_back(i);
      if (x > 12 - 1e-9) {
        bc.prescribed_nodes.push_back(i);
        for (const double d : {4.0, 0.0, 0.0}) bc.prescribed_displacements.push_back(d);
      }
    }
    const FemStaticResult r = solve_fem_static(model, bc, FemLoads{}, FemStaticOptions{});
    EXPECT_TRUE(r.report.converged) << fem_law_name(material.law);
    return r.displacements;
  };
  const FemMaterial mr0 = fem_material_from_constants(FemLaw::mooney_rivlin, {5000, 0}, 0.45, 1.06e-3);
  FemMaterial nh = mr0;
  nh.law = FemLaw::neo_hookean;
  nh.constants = {0, 0};
  const auto u_mr0 = solve(mr0), u_nh = solve(nh);
  ASSERT_EQ(u_mr0.size(), u_nh.size());
  double worst = 0;
  for (size_t i = 0; i < u_nh.size(); ++i) worst = std::max(worst, std::abs(u_mr0[i] - u_nh[i]));
  EXPECT_LT(worst, 1e-6);
  const auto u_mr = solve(fem_material_from_constants(FemLaw::mooney_rivlin, {2500, 2500}, 0.45, 1.06e-3));
  double moved = 0;
  for (size_t i = 0; i < u_nh.size(); ++i) moved = std::max(moved, std::abs(u_mr[i] - u_nh[i]));
  EXPECT_GT(moved, 1e-3);  // the lateral contraction differs at 33 % stretch
}

}  // namespace
}  // namespace ctsurg::sim
