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
  for (auto model : {FemMaterialModel::linear, FemMaterialModel::stvk, FemMaterialModel::neo_hookean}) {
    M9 P;
    ASSERT_TRUE(first_piola_kirchhoff(model, l, I, P));
    for (double p : P) EXPECT_NEAR(p, 0, 1e-9) << fem_material_model_name(model);
    EXPECT_NEAR(strain_energy_density(model, l, I), 0, 1e-9);
  }
  const M9 R = rotation(1.2);
  for (auto model : {FemMaterialModel::stvk, FemMaterialModel::neo_hookean}) {
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
  M9 lin, stvk, nh;
  first_piola_kirchhoff(FemMaterialModel::linear, l, F, lin);
  first_piola_kirchhoff(FemMaterialModel::stvk, l, F, stvk);
  first_piola_kirchhoff(FemMaterialModel::neo_hookean, l, F, nh);
  for (int i = 0; i < 9; ++i) {
    EXPECT_NEAR(stvk[i], lin[i], 1e-3 * 1e4 * 1e-6 * 10);
    EXPECT_NEAR(nh[i], lin[i], 1e-3 * 1e4 * 1e-6 * 10);
  }
}

TEST(FemMaterial, StressIsTheEnergyDerivative) {
  const LameParameters l{1e4, 4e4};
  const M9 F = mul(rotation(0.4), M9{1.2, 0.1, 0.0, -0.05, 0.9, 0.08, 0.02, 0.0, 1.1});
  for (auto model : {FemMaterialModel::linear, FemMaterialModel::stvk, FemMaterialModel::neo_hookean}) {
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
