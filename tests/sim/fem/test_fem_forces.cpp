// Tests of sim/fem_forces.h: rigid motions, tangent stiffness against finite differences, balance,
// thread-count determinism.
#include "ctsurg/sim/fem/fem_forces.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/fem/fem_box_mesh.h"
#include "fem_test_models.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ctsurg::sim {
namespace {

using test::max_abs;

FemModel block(FemLaw model, std::array<int, 3> cells = {4, 3, 3}) {
  const auto box = fem_box_mesh(cells, {8.0, 6.0, 6.0}, {-4, -3, -3});
  FemMaterial m;
  m.law = model;
  m.youngs_modulus = 3e4;
  m.poisson_ratio = 0.45;
  return build_fem_model(box.nodes, box.tets, m);
}

// Displacements that rotate the rest mesh by `angle` about (1, 2, 2)/3 and translate it by (5, -2, 1).
std::vector<double> rigid_motion(const FemModel& m, double angle) {
  const double x = 1.0 / 3, y = 2.0 / 3, z = 2.0 / 3, c = std::cos(angle), s = std::sin(angle), t = 1 - c;
  const double R[9] = {t * x * x + c,     t * x * y - s * z, t * x * z + s * y, t * x * y + s * z, t * y * y + c,
                       t * y * z - s * x, t * x * z - s * y, t * y * z + s * x, t * z * z + c};
  std::vector<double> u(m.nodes.size());
  const double shift[3] = {5, -2, 1};
  for (int32_t i = 0; i < m.node_count(); ++i)
    for (int r = 0; r < 3; ++r) {
      double v = shift[r] - m.nodes[3 * i + r];
      for (int k = 0; k < 3; ++k) v += R[r * 3 + k] * m.nodes[3 * i + k];
      u[3 * i + r] = v;
    }
  return u;
}

TEST(FemForces, LargeRigidRotationGivesNoForceForNonlinearModelsButSpuriousForLinear) {
  // A 90-degree rotation of an unloaded block. Force scale: E times a face area of ~4 mm^2 ~ 1e5 uN.
  for (auto model : {FemLaw::stvk, FemLaw::neo_hookean, FemLaw::corotational,
                     FemLaw::linear}) {
    const FemModel m = block(model);
    std::vector<double> f;
    EXPECT_EQ(fem_internal_forces(m, rigid_motion(m, M_PI / 2), f), -1);
    const double fmax = max_abs(f);
    const double energy = fem_strain_energy(m, rigid_motion(m, M_PI / 2));
    if (model == FemLaw::linear) {
      EXPECT_GT(fmax, 1e4) << "linear: spurious forces of a rotation, max " << fmax << " uN";
      EXPECT_GT(energy, 1e5);
      std::cout << "linear elasticity under a 90-degree rigid rotation: max nodal force " << fmax
                << " uN, strain energy " << energy << " nJ\n";
    } else {
      EXPECT_LT(fmax, 1e-6) << fem_law_name(model);
      EXPECT_LT(std::abs(energy), 1e-6) << fem_law_name(model);
    }
  }
}

TEST(FemForces, ElementStiffnessIsTheForceDerivative) {
  for (auto model : {FemLaw::linear, FemLaw::stvk, FemLaw::neo_hookean}) {
    const FemModel m = block(model, {1, 1, 1});
    std::vector<double> u = rigid_motion(m, 0.3);
    for (std::size_t d = 0; d < u.size(); ++d) u[d] += 0.2 * std::sin(1.7 * d + 0.3);  // a general deformation
    const int32_t e = 2;
    const auto K = fem_element_stiffness(m, e, u);
    for (int c = 0; c < 12; ++c) {
      const double h = 1e-6;
      auto up = u, um = u;
      up[3 * m.tets[4 * e + c / 3] + c % 3] += h;
      um[3 * m.tets[4 * e + c / 3] + c % 3] -= h;
      // The element's own forces: all other elements are affected too, so difference the single
      // element's energy gradient through its stress instead.
      auto element_force = [&](const std::vector<double>& v) {
        const auto P = fem_element_stress(m, e, v);
        std::array<double, 12> f{};
        const double* B = &m.dm_inverse[9 * e];
        for (int r = 0; r < 3; ++r) {
          double s = 0;
          for (int a = 1; a < 4; ++a) {
            f[3 * a + r] = -m.rest_volume[e] * (P[r * 3] * B[(a - 1) * 3] + P[r * 3 + 1] * B[(a - 1) * 3 + 1] +
                                                P[r * 3 + 2] * B[(a - 1) * 3 + 2]);
            s += f[3 * a + r];
          }
          f[r] = -s;
        }
        return f;
      };
      const auto fp = element_force(up), fm = element_force(um);
      for (int r = 0; r < 12; ++r) {
        const double fd = -(fp[r] - fm[r]) / (2 * h);
        EXPECT_NEAR(K[r * 12 + c], fd, 1e-5 * std::max(1.0, std::abs(fd)) + 1e-3)
            << fem_law_name(model) << " K(" << r << ", " << c << ")";
      }
    }
    for (int r = 0; r < 12; ++r)
      for (int c = 0; c < 12; ++c) EXPECT_NEAR(K[r * 12 + c], K[c * 12 + r], 1e-6 * std::abs(K[r * 12 + r]));
  }
}

TEST(FemForces, ForcesBalanceAndAreIdenticalForAnyThreadCount) {
  const FemModel m = block(FemLaw::neo_hookean, {10, 8, 8});
  std::vector<double> u(m.nodes.size());
  for (std::size_t d = 0; d < u.size(); ++d) u[d] = 0.1 * std::sin(0.37 * d);
  std::vector<double> f1, f2, f3;
  ASSERT_EQ(fem_internal_forces(m, u, f1, 1), -1);
  fem_internal_forces(m, u, f2, 2);
  fem_internal_forces(m, u, f3, 3);
  EXPECT_EQ(f1, f2);
  EXPECT_EQ(f1, f3);
  double sum[3] = {0, 0, 0};
  for (int32_t i = 0; i < m.node_count(); ++i)
    for (int c = 0; c < 3; ++c) sum[c] += f1[3 * i + c];
  for (double s : sum) EXPECT_NEAR(s, 0, 1e-7 * max_abs(f1));
}

TEST(FemForces, InvertedElementIsReportedAndGivesNoNaN) {
  const FemModel m = block(FemLaw::neo_hookean, {1, 1, 1});
  std::vector<double> u(m.nodes.size(), 0.0);
  u[3 * 7] = -30;  // drag the far corner through the block
  std::vector<double> f;
  EXPECT_GE(fem_internal_forces(m, u, f), 0);
  for (double v : f) EXPECT_TRUE(std::isfinite(v));
  EXPECT_THROW(fem_internal_forces(m, std::vector<double>(5), f), InputError);
}

}  // namespace
}  // namespace ctsurg::sim
