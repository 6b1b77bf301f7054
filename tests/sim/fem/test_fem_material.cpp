// Tests of sim/fem_material.h: parameter checks, Lame parameters, the three stress laws.
#include "ctsurg/sim/fem/fem_material.h"

#include "ctsurg/core/error.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ctsurg::sim {
namespace {

using M9 = std::array<double, 9>;

M9 mul(const M9& a, const M9& b) {
  M9 c{};
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k)
      for (int s = 0; s < 3; ++s) c[r * 3 + s] += a[r * 3 + k] * b[k * 3 + s];
  return c;
}

M9 rotation(double angle) {  // about the axis (1, 2, 2) / 3
  const double x = 1.0 / 3, y = 2.0 / 3, z = 2.0 / 3, c = std::cos(angle), s = std::sin(angle), t = 1 - c;
  return {t * x * x + c,     t * x * y - s * z, t * x * z + s * y, t * x * y + s * z, t * y * y + c,
          t * y * z - s * x, t * x * z - s * y, t * y * z + s * x, t * z * z + c};
}

TEST(FemMaterial, RejectsOutOfRangeParametersNamingTheField) {
  FemMaterial m;
  m.poisson_ratio = 0.5;
  try {
    lame_parameters(m);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "poisson_ratio");
  }
  m.poisson_ratio = -1;
  EXPECT_THROW(lame_parameters(m), InputError);
  m.poisson_ratio = 0.3;
  m.youngs_modulus = 0;
  try {
    lame_parameters(m);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "youngs_modulus");
  }
  m.youngs_modulus = 1e4;
  m.density = -1;
  EXPECT_THROW(validate_fem_material(m), InputError);
}

TEST(FemMaterial, LameParameters) {
  FemMaterial m;
  m.youngs_modulus = 2.6e4;
  m.poisson_ratio = 0.3;
  const auto l = lame_parameters(m);
  EXPECT_NEAR(l.mu, 1e4, 1e-9);
  EXPECT_NEAR(l.lambda, 2.6e4 * 0.3 / (1.3 * 0.4), 1e-9);
}

TEST(FemMaterial, StressFreeAtRestAndUnderRotationForNonlinearModels) {
  const LameParameters l{1e4, 4e4};
  const M9 I{1, 0, 0, 0, 1, 0, 0, 0, 1};
  for (auto model : {FemMaterialModel::linear, FemMaterialModel::stvk, FemMaterialModel::neo_hookean,
                     FemMaterialModel::corotational}) {
    M9 P;
    ASSERT_TRUE(first_piola_kirchhoff(model, l, I, P));
    for (double p : P) EXPECT_NEAR(p, 0, 1e-9) << fem_material_model_name(model);
    EXPECT_NEAR(strain_energy_density(model, l, I), 0, 1e-9);
  }
  const M9 R = rotation(1.2);
  for (auto model : {FemMaterialModel::stvk, FemMaterialModel::neo_hookean, FemMaterialModel::corotational}) {
    M9 P;
    ASSERT_TRUE(first_piola_kirchhoff(model, l, R, P));
    for (double p : P) EXPECT_NEAR(p, 0, 1e-8) << fem_material_model_name(model);
  }
  M9 P;
  ASSERT_TRUE(first_piola_kirchhoff(FemMaterialModel::linear, l, R, P));
  double norm = 0;
  for (double p : P) norm += p * p;
  EXPECT_GT(std::sqrt(norm), 1e4) << "small-strain elasticity sees a rotation as strain";
}

TEST(FemMaterial, AllModelsAgreeForSmallStrain) {
  const LameParameters l{1e4, 4e4};
  const M9 F{1 + 1e-6, 2e-6, -1e-6, 0.5e-6, 1 - 2e-6, 1e-6, 3e-6, 0, 1 + 0.7e-6};
  M9 lin, stvk, nh, cr;
  first_piola_kirchhoff(FemMaterialModel::linear, l, F, lin);
  first_piola_kirchhoff(FemMaterialModel::stvk, l, F, stvk);
  first_piola_kirchhoff(FemMaterialModel::neo_hookean, l, F, nh);
  first_piola_kirchhoff(FemMaterialModel::corotational, l, F, cr);
  for (int i = 0; i < 9; ++i) {
    EXPECT_NEAR(stvk[i], lin[i], 1e-3 * 1e4 * 1e-6 * 10);
    EXPECT_NEAR(nh[i], lin[i], 1e-3 * 1e4 * 1e-6 * 10);
    EXPECT_NEAR(cr[i], lin[i], 1e-3 * 1e4 * 1e-6 * 10);
  }
}

TEST(FemMaterial, StressIsTheEnergyDerivative) {
  const LameParameters l{1e4, 4e4};
  const M9 F = mul(rotation(0.4), M9{1.2, 0.1, 0.0, -0.05, 0.9, 0.08, 0.02, 0.0, 1.1});
  for (auto model : {FemMaterialModel::linear, FemMaterialModel::stvk, FemMaterialModel::neo_hookean,
                     FemMaterialModel::corotational}) {
    M9 P;
    ASSERT_TRUE(first_piola_kirchhoff(model, l, F, P));
    for (int i = 0; i < 9; ++i) {
      const double h = 1e-6;
      M9 a = F, b = F;
      a[i] += h;
      b[i] -= h;
      const double d = (strain_energy_density(model, l, a) - strain_energy_density(model, l, b)) / (2 * h);
      EXPECT_NEAR(P[i], d, 1e-5 * 1e4) << fem_material_model_name(model) << " entry " << i;
    }
  }
}

// Corotational elasticity is the linear law in each element's rotated frame: any rotation of a
// stretch gives the rotated stress of the stretch, and a uniaxial stretch gives the linear stress,
// which departs from Neo-Hookean's as the stretch grows (the closed forms below; the figures go into
// docs/fem.md).
TEST(FemMaterial, CorotationalIsLinearInTheRotatedFrameAndDepartsFromNeoHookeanInStretch) {
  const LameParameters l{1e4, 9e4};  // nu = 0.45
  const M9 S{1.1, 0.05, 0.0, 0.05, 0.95, 0.02, 0.0, 0.02, 1.03};  // symmetric: already "rotated back"
  const M9 R = rotation(0.9);
  M9 ps, pr, lin;
  ASSERT_TRUE(first_piola_kirchhoff(FemMaterialModel::corotational, l, S, ps));
  ASSERT_TRUE(first_piola_kirchhoff(FemMaterialModel::corotational, l, mul(R, S), pr));
  ASSERT_TRUE(first_piola_kirchhoff(FemMaterialModel::linear, l, S, lin));
  const M9 rotated = mul(R, ps);
  for (int i = 0; i < 9; ++i) {
    EXPECT_NEAR(ps[i], lin[i], 1e-9 * 1e4);       // a symmetric F: exactly the linear law
    EXPECT_NEAR(pr[i], rotated[i], 1e-9 * 1e4);   // rotated: the same stress, rotated
  }
  EXPECT_NEAR(strain_energy_density(FemMaterialModel::corotational, l, mul(R, S)),
              strain_energy_density(FemMaterialModel::linear, l, S), 1e-9);
  // Uniaxial stretch a (lateral b = 1): P11 = (2 mu + lambda)(a - 1) for corotational; Neo-Hookean
  // P11 = mu (a - 1/a) + lambda ln(a) / a (nu = 0.45): 0.1 % apart at 0.1 % stretch, 41 % at 30 % stretch,
  // 26 % at 20 % compression.
  for (const auto& [a, close] : std::vector<std::pair<double, bool>>{{1.001, true}, {1.3, false}, {0.8, false}}) {
    const M9 F{a, 0, 0, 0, 1, 0, 0, 0, 1};
    M9 c, n;
    first_piola_kirchhoff(FemMaterialModel::corotational, l, F, c);
    first_piola_kirchhoff(FemMaterialModel::neo_hookean, l, F, n);
    EXPECT_NEAR(c[0], (2 * l.mu + l.lambda) * (a - 1), 1e-9 * 1e5);
    EXPECT_NEAR(n[0], l.mu * (a - 1 / a) + l.lambda * std::log(a) / a, 1e-9 * 1e5);
    const double gap = std::abs(c[0] - n[0]) / std::abs(n[0]);
    std::printf("uniaxial stretch %.3f: corotational P11 %.0f Pa, Neo-Hookean %.0f Pa (%.1f %% apart)\n", a, c[0], n[0], 100 * gap);
    if (close) {
      EXPECT_LT(gap, 0.01);
    } else {
      EXPECT_GT(gap, 0.1);
    }
  }
}

TEST(FemMaterial, InvertedDeformationGivesFalseNotNaN) {
  const LameParameters l{1e4, 4e4};
  const M9 F{-1, 0, 0, 0, 1, 0, 0, 0, 1};
  for (auto model : {FemMaterialModel::linear, FemMaterialModel::stvk, FemMaterialModel::neo_hookean}) {
    M9 P;
    EXPECT_FALSE(first_piola_kirchhoff(model, l, F, P));
    for (double p : P) EXPECT_EQ(p, 0);
  }
  EXPECT_TRUE(std::isinf(strain_energy_density(FemMaterialModel::neo_hookean, l, F)));
}

}  // namespace
}  // namespace ctsurg::sim
