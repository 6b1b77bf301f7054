// Tests of sim/fem/fem_material.h and the laws of sim/fem/laws/: parameter checks, Lame parameters, the
// law registry, and the properties every law must have (checked for each id of FemLaw, so a new law is
// tested the day it is registered).
#include "ctsurg/sim/fem/fem_material.h"
#include "ctsurg/sim/fem/laws/fem_law.h"

#include "ctsurg/core/error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

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
  for (auto model : {FemLaw::linear, FemLaw::stvk, FemLaw::neo_hookean,
                     FemLaw::corotational}) {
    M9 P;
    ASSERT_TRUE(first_piola_kirchhoff(model, l, I, P));
    for (double p : P) EXPECT_NEAR(p, 0, 1e-9) << fem_law_name(model);
    EXPECT_NEAR(strain_energy_density(model, l, I), 0, 1e-9);
  }
  const M9 R = rotation(1.2);
  for (auto model : {FemLaw::stvk, FemLaw::neo_hookean, FemLaw::corotational}) {
    M9 P;
    ASSERT_TRUE(first_piola_kirchhoff(model, l, R, P));
    for (double p : P) EXPECT_NEAR(p, 0, 1e-8) << fem_law_name(model);
  }
  M9 P;
  ASSERT_TRUE(first_piola_kirchhoff(FemLaw::linear, l, R, P));
  double norm = 0;
  for (double p : P) norm += p * p;
  EXPECT_GT(std::sqrt(norm), 1e4) << "small-strain elasticity sees a rotation as strain";
}

TEST(FemMaterial, AllModelsAgreeForSmallStrain) {
  const LameParameters l{1e4, 4e4};
  const M9 F{1 + 1e-6, 2e-6, -1e-6, 0.5e-6, 1 - 2e-6, 1e-6, 3e-6, 0, 1 + 0.7e-6};
  M9 lin, stvk, nh, cr;
  first_piola_kirchhoff(FemLaw::linear, l, F, lin);
  first_piola_kirchhoff(FemLaw::stvk, l, F, stvk);
  first_piola_kirchhoff(FemLaw::neo_hookean, l, F, nh);
  first_piola_kirchhoff(FemLaw::corotational, l, F, cr);
  for (int i = 0; i < 9; ++i) {
    EXPECT_NEAR(stvk[i], lin[i], 1e-3 * 1e4 * 1e-6 * 10);
    EXPECT_NEAR(nh[i], lin[i], 1e-3 * 1e4 * 1e-6 * 10);
    EXPECT_NEAR(cr[i], lin[i], 1e-3 * 1e4 * 1e-6 * 10);
  }
}

TEST(FemMaterial, StressIsTheEnergyDerivative) {
  const LameParameters l{1e4, 4e4};
  const M9 F = mul(rotation(0.4), M9{1.2, 0.1, 0.0, -0.05, 0.9, 0.08, 0.02, 0.0, 1.1});
  for (auto model : {FemLaw::linear, FemLaw::stvk, FemLaw::neo_hookean,
                     FemLaw::corotational}) {
    M9 P;
    ASSERT_TRUE(first_piola_kirchhoff(model, l, F, P));
    for (int i = 0; i < 9; ++i) {
      const double h = 1e-6;
      M9 a = F, b = F;
      a[i] += h;
      b[i] -= h;
      const double d = (strain_energy_density(model, l, a) - strain_energy_density(model, l, b)) / (2 * h);
      EXPECT_NEAR(P[i], d, 1e-5 * 1e4) << fem_law_name(model) << " entry " << i;
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
  ASSERT_TRUE(first_piola_kirchhoff(FemLaw::corotational, l, S, ps));
  ASSERT_TRUE(first_piola_kirchhoff(FemLaw::corotational, l, mul(R, S), pr));
  ASSERT_TRUE(first_piola_kirchhoff(FemLaw::linear, l, S, lin));
  const M9 rotated = mul(R, ps);
  for (int i = 0; i < 9; ++i) {
    EXPECT_NEAR(ps[i], lin[i], 1e-9 * 1e4);       // a symmetric F: exactly the linear law
    EXPECT_NEAR(pr[i], rotated[i], 1e-9 * 1e4);   // rotated: the same stress, rotated
  }
  EXPECT_NEAR(strain_energy_density(FemLaw::corotational, l, mul(R, S)),
              strain_energy_density(FemLaw::linear, l, S), 1e-9);
  // Uniaxial stretch a (lateral b = 1): P11 = (2 mu + lambda)(a - 1) for corotational; Neo-Hookean
  // P11 = mu (a - 1/a) + lambda ln(a) / a (nu = 0.45): 0.1 % apart at 0.1 % stretch, 41 % at 30 % stretch,
  // 26 % at 20 % compression.
  for (const auto& [a, close] : std::vector<std::pair<double, bool>>{{1.001, true}, {1.3, false}, {0.8, false}}) {
    const M9 F{a, 0, 0, 0, 1, 0, 0, 0, 1};
    M9 c, n;
    first_piola_kirchhoff(FemLaw::corotational, l, F, c);
    first_piola_kirchhoff(FemLaw::neo_hookean, l, F, n);
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
  for (auto model : {FemLaw::linear, FemLaw::stvk, FemLaw::neo_hookean}) {
    M9 P;
    EXPECT_FALSE(first_piola_kirchhoff(model, l, F, P));
    for (double p : P) EXPECT_EQ(p, 0);
  }
  EXPECT_TRUE(std::isinf(strain_energy_density(FemLaw::neo_hookean, l, F)));
}

// Every registered law, with constants for the small-strain moduli mu, lambda (mooney_rivlin: mu split
// 60 / 40 between c10 and c01).
std::vector<FemLawParameters<double>> every_law(double mu, double lambda) {
  std::vector<FemLawParameters<double>> laws;
  for (int32_t id = 0; id < kFemLawCount; ++id) {
    FemLawParameters<double> k{static_cast<FemLaw>(id), mu, lambda, {0, 0}};
    if (fem_law_info(k.law).constant_count == 2) k.c[0] = 0.3 * mu, k.c[1] = 0.2 * mu;
    laws.push_back(k);
  }
  return laws;
}

TEST(FemLaws, NamesRoundTripAndUnknownNamesAreRefused) {
  EXPECT_EQ(fem_law_names(), "linear, stvk, neo_hookean, corotational, mooney_rivlin");
  for (int32_t id = 0; id < kFemLawCount; ++id) {
    const auto law = static_cast<FemLaw>(id);
    EXPECT_EQ(fem_law_named(fem_law_name(law)), law);
  }
  EXPECT_FALSE(fem_law_named("neohookean").has_value());
  FemMaterial m;
  m.law = static_cast<FemLaw>(kFemLawCount);
  try {
    validate_fem_material(m);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "law");
    EXPECT_NE(e.problem().find("mooney_rivlin"), std::string::npos) << e.what();
  }
}

// For every law: P is dpsi/dF and A is dP/dF (central differences), zero stress and energy at rest,
// linear elasticity with the same mu and lambda at small strain, and the traits the law declares:
// infinite energy for det F <= 0 when it needs J > 0, a positive semi-definite tangent when it says its
// tangent is never indefinite.
TEST(FemLaws, EveryLawIsConsistentWithItsEnergyTangentAndTraits) {
  const double mu = 1e4, lambda = 4e4;
  const M9 I{1, 0, 0, 0, 1, 0, 0, 0, 1};
  const std::vector<M9> deformations = {mul(rotation(0.4), M9{1.2, 0.1, 0.0, -0.05, 0.9, 0.08, 0.02, 0.0, 1.1}),
                                        M9{0.7, 0.2, 0.0, 0.1, 0.8, -0.1, 0.0, 0.05, 0.75},
                                        M9{1.5, 0.3, 0.1, 0.0, 1.1, 0.2, -0.1, 0.0, 1.3}};
  for (const auto& k : every_law(mu, lambda)) {
    const char* name = fem_law_name(k.law);
    SCOPED_TRACE(name);
    M9 P;
    ASSERT_TRUE(first_piola_kirchhoff(k, I, P));
    for (double p : P) EXPECT_NEAR(p, 0, 1e-9);
    EXPECT_NEAR(strain_energy_density(k, I), 0, 1e-9);
    if (k.law != FemLaw::linear) {  // every other law is rotation invariant: a rigid rotation is stress free
      ASSERT_TRUE(first_piola_kirchhoff(k, rotation(1.2), P));
      for (double p : P) EXPECT_NEAR(p, 0, 1e-8);
    }
    for (const M9& F : deformations) {
      std::array<double, 81> A{};
      ASSERT_TRUE(first_piola_kirchhoff(k, F, P));
      ASSERT_TRUE(material_tangent(k, F, A));
      for (int i = 0; i < 9; ++i) {
        const double h = 1e-6;
        M9 a = F, b = F, pa, pb;
        a[i] += h;
        b[i] -= h;
        const double d = (strain_energy_density(k, a) - strain_energy_density(k, b)) / (2 * h);
        EXPECT_NEAR(P[i], d, 1e-5 * mu) << "P entry " << i;
        first_piola_kirchhoff(k, a, pa);
        first_piola_kirchhoff(k, b, pb);
        // The corotational tangent leaves out dR/dF by design (a quasi-Newton tangent): only at rest.
        if (k.law == FemLaw::corotational) continue;
        for (int r = 0; r < 9; ++r) EXPECT_NEAR(A[r * 9 + i], (pa[r] - pb[r]) / (2 * h), 1e-4 * mu) << "A entry " << r << ", " << i;
      }
      if (!fem_law_traits(k.law).indefinite_tangent) {
        // x^T A x >= 0 for a spread of directions x (the 9 unit vectors and their pairwise sums/differences).
        for (int i = 0; i < 9; ++i)
          for (int j = i; j < 9; ++j)
            for (const double sign : {1.0, -1.0}) {
              double x[9] = {0};
              x[i] += 1, x[j] += sign;
              double q = 0;
              for (int r = 0; r < 9; ++r)
                for (int c = 0; c < 9; ++c) q += x[r] * A[r * 9 + c] * x[c];
              EXPECT_GE(q, -1e-9 * mu);
            }
      }
    }
    // Small strain: linear elasticity with mu, lambda (to the strain's square).
    const M9 Fs{1 + 1e-6, 2e-6, -1e-6, 0.5e-6, 1 - 2e-6, 1e-6, 3e-6, 0, 1 + 0.7e-6};
    M9 lin, p;
    ASSERT_TRUE(first_piola_kirchhoff(FemLawParameters<double>{FemLaw::linear, mu, lambda, {0, 0}}, Fs, lin));
    ASSERT_TRUE(first_piola_kirchhoff(k, Fs, p));
    for (int i = 0; i < 9; ++i) EXPECT_NEAR(p[i], lin[i], 1e-3 * mu * 1e-6 * 10);
    // det F < 0.
    const M9 inverted{-1, 0, 0, 0, 1, 0, 0, 0, 1};
    EXPECT_FALSE(first_piola_kirchhoff(k, inverted, P));
    for (double v : P) EXPECT_EQ(v, 0);
    if (fem_law_traits(k.law).needs_positive_j) {
      EXPECT_TRUE(std::isinf(strain_energy_density(k, inverted)));
    }
  }
}

}  // namespace
}  // namespace ctsurg::sim
