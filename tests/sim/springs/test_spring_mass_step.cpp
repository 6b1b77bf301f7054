#include "ctsurg/sim/springs/spring_mass_step.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/springs/explicit_spring_model.h"
#include "ctsurg/sim/springs/stability.h"
#include "sim_test_models.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace ctsurg::sim {
namespace {

using test::block_occupancy;
using test::perturb;
using test::test_material;

double max_abs_difference(const ParticleState& a, const ParticleState& b) {
  double m = 0;
  for (int32_t i = 0; i < a.count(); ++i)
    m = std::max({m, std::abs(double(a.x[i]) - b.x[i]), std::abs(double(a.y[i]) - b.y[i]),
                  std::abs(double(a.z[i]) - b.z[i])});
  return m;
}

bool step_all_finite(const ParticleState& s) {
  for (int32_t i = 0; i < s.count(); ++i)
    if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i]) || !std::isfinite(s.z[i])) return false;
  return true;
}

// Total energy at the step being taken: spring energy at x(t) and kinetic energy from the central
// difference (x(t + dt) - x(t - dt)) / (2 dt), the velocity that Verlet conserves energy with.
template <class Model>
double energy_over_step(const Model& model, ParticleState& s, const StepParameters& p) {
  const std::vector<Real> bx = s.px, by = s.py, bz = s.pz;
  const double potential = spring_energy(model, s);
  step(model, s, p);
  double kinetic = 0;
  for (int32_t i = 0; i < s.count(); ++i) {
    const double vx = (double(s.x[i]) - bx[i]) / (2 * p.dt), vy = (double(s.y[i]) - by[i]) / (2 * p.dt),
                 vz = (double(s.z[i]) - bz[i]) / (2 * p.dt);
    kinetic += 0.5 * s.mass[i] * (vx * vx + vy * vy + vz * vz);
  }
  return potential + kinetic;
}

TEST(SpringMassStep, UndampedEnergyStaysBoundedOver1e5StepsAtTheAutoStep) {
  const auto model = build_spring_grid_model(block_occupancy(4, 4, 4, 2.0), test_material(1000, 500));
  auto s = model.make_state();
  perturb(s, 0.2);
  StepParameters p;
  p.dt = critical_time_step(model).dt;
  p.threads = 1;
  const double e0 = energy_over_step(model, s, p);
  ASSERT_GT(e0, 0);
  double low = e0, high = e0;
  for (int block = 1; block < 1000; ++block) {
    for (int n = 0; n < 99; ++n) step(model, s, p);
    const double e = energy_over_step(model, s, p);
    low = std::min(low, e), high = std::max(high, e);
  }
  ASSERT_TRUE(step_all_finite(s));
  // Verlet conserves a shadow energy: the measured energy oscillates below e0 (all potential at the
  // start) by a few percent (order (omega dt)^2, 4 % here) and does not drift; an unstable or
  // energy-pumping step would leave the band within a few hundred steps.
  EXPECT_GT(low, 0.9 * e0);
  EXPECT_LT(high, 1.1 * e0);
}

// Centre of mass, mm (double sums of the float positions).
std::array<double, 3> centre_of_mass(const ParticleState& s) {
  std::array<double, 3> c{0, 0, 0};
  double m = 0;
  for (int32_t i = 0; i < s.count(); ++i) c[0] += s.mass[i] * s.x[i], c[1] += s.mass[i] * s.y[i], c[2] += s.mass[i] * s.z[i], m += s.mass[i];
  for (double& v : c) v /= m;
  return c;
}

TEST(SpringMassStep, MomentumIsConservedWithoutExternalForces) {
  // Conserved momentum = the centre of mass moves in a straight line at the initial drift velocity.
  // (Measured on the centre of mass rather than on m (x - px) / dt: one step moves a particle by a few
  // float ulps of its position, too coarse for a per-step velocity.)
  const auto model = build_spring_grid_model(block_occupancy(5, 3, 4, 1.5), test_material(2000, 1000, 0.5));
  auto s = model.make_state();
  perturb(s, 0.2);
  StepParameters p;
  p.dt = critical_time_step(model).dt;
  const std::array<double, 3> v{3.0, -1.0, 2.0};  // mm/s
  for (int32_t i = 0; i < s.count(); ++i) s.set_velocity(i, v[0], v[1], v[2], p.dt);
  const auto c0 = centre_of_mass(s);
  const int steps = 2000;
  for (int n = 0; n < steps; ++n) step(model, s, p);
  const auto c1 = centre_of_mass(s);
  // An unbalanced spring force (a missing or doubled term: ~k 0.1 mm = 100 uN on 0.2 g) would move
  // the centre by metres. Float rounding does move it: each step rounds every position to ~1e-6 mm, a
  // velocity kick that Verlet keeps, so the centre wanders by ~ulp N^1.5 / sqrt(P) = 3e-3 mm here,
  // 0.15 % of the 2.25 mm travel.
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(c1[a] - c0[a], v[a] * p.dt * steps, 0.01 * 3.0 * p.dt * steps) << "axis " << a;
  const auto p0 = momentum(s, p.dt);
  double total_mass = 0;
  for (Real m : s.mass) total_mass += m;
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(p0[a], total_mass * v[a], 0.02 * total_mass * 3.0) << "axis " << a;
}

TEST(SpringMassStep, HangingChainReachesTheStaticElongationOfItsSprings) {
  // A 1 x 1 x N column: face springs only, along z. Spring s (from the bottom, s = 1..N-1) carries the
  // weight of the s particles below it: elongation s m g / k.
  const int n = 10;
  const double h = 5.0, k = 1e5, g = 9810;
  const auto model = build_spring_grid_model(block_occupancy(1, 1, n, h), test_material(k, 0));
  auto s = model.make_state();
  const int32_t top = model.particle_at(1, 1, n);
  s.set_fixed(top, true);
  StepParameters p;
  p.dt = critical_time_step(model).dt;
  p.damping = 0.02;
  p.gravity = {0, 0, -g};
  for (int q = 0; q < 10000; ++q) step(model, s, p);
  // At rest the positions still jitter by a few float ulps (ulp(70 mm) = 7.6e-6 mm, amplified by the
  // lightly damped modes); their time average is the static solution.
  std::vector<double> z(s.count(), 0.0);
  const int average = 2000;
  for (int q = 0; q < average; ++q) {
    step(model, s, p);
    for (int32_t i = 0; i < s.count(); ++i) z[i] += double(s.z[i]) / average;
  }
  const double unit = model.mass[0] * g / k;  // 0.0123 mm
  for (int level = 1; level < n; ++level) {
    const int32_t a = model.particle_at(1, 1, level), b = model.particle_at(1, 1, level + 1);
    EXPECT_NEAR(z[b] - z[a] - h, level * unit, 0.01 * unit) << "spring above level " << level;
    EXPECT_EQ(s.x[a], model.rest_positions[3 * a]);
    EXPECT_EQ(s.y[a], model.rest_positions[3 * a + 1]);
  }
  const int32_t bottom = model.particle_at(1, 1, 1);
  EXPECT_NEAR(model.rest_positions[3 * bottom + 2] - z[bottom], unit * n * (n - 1) / 2, 1e-3 * unit * n * (n - 1) / 2);
  EXPECT_EQ(s.z[top], model.rest_positions[3 * top + 2]);  // fixed
}

template <class Model>
ParticleState run_with_threads(const Model& model, int threads, ParticleNormals* normals) {
  auto s = model.make_state();
  perturb(s, 0.3);
  StepParameters p;
  p.dt = critical_time_step(model).dt;
  p.damping = 0.001;
  p.gravity = {0, 0, -9810};
  p.threads = threads;
  s.set_fixed(0, true);
  for (int n = 0; n < 100; ++n) step(model, s, p, normals);
  return s;
}

bool bit_identical(const std::vector<Real>& a, const std::vector<Real>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Real)) == 0;
}

TEST(SpringMassStep, ResultsAreBitIdenticalOnOneAndTwoThreads) {
  // A block with holes (both kernel paths), not a multiple of the SIMD width or of the partition block.
  const auto grid = build_spring_grid_model(test::holed_block_occupancy(11, 15, 7, 2.0), test_material(1000, 700, 0.3));
  int regular = 0;
  for (int32_t o : grid.chunk_offsets) regular += o != kIrregularChunk;
  EXPECT_GT(regular, 0);
  EXPECT_LT(regular, static_cast<int>(grid.chunk_offsets.size()));
  const auto expl = explicit_model_from_grid(grid);
  ParticleNormals n1, n2;
  const auto g1 = run_with_threads(grid, 1, &n1), g2 = run_with_threads(grid, 2, &n2);
  EXPECT_TRUE(bit_identical(g1.x, g2.x) && bit_identical(g1.y, g2.y) && bit_identical(g1.z, g2.z));
  EXPECT_TRUE(bit_identical(g1.px, g2.px));
  EXPECT_TRUE(bit_identical(n1.x, n2.x) && bit_identical(n1.y, n2.y) && bit_identical(n1.z, n2.z));
  const auto e1 = run_with_threads(expl, 1, nullptr), e2 = run_with_threads(expl, 2, nullptr);
  EXPECT_TRUE(bit_identical(e1.x, e2.x) && bit_identical(e1.y, e2.y) && bit_identical(e1.z, e2.z));
  EXPECT_GT(max_abs_difference(g1, grid.make_state()), 0.1);  // it did move
}

TEST(SpringMassStep, ContiguousAndGatheringKernelPathsGiveTheSameBits) {
  // The CPU kernel reads a regular chunk's neighbours contiguously (SpringGridModel::chunk_offsets);
  // marking every chunk irregular forces the gathering path, which must give the same positions.
  auto fast = build_spring_grid_model(block_occupancy(9, 8, 6, 2.0), test_material(1000, 700, 0.3));
  cut_grid_spring(fast, 40, 6);  // a cut spring inside a regular chunk: bit 0, read contiguously
  auto gathered = fast;
  std::fill(gathered.chunk_offsets.begin(), gathered.chunk_offsets.end(), kIrregularChunk);
  ParticleNormals n1, n2;
  const auto a = run_with_threads(fast, 1, &n1), b = run_with_threads(gathered, 1, &n2);
  EXPECT_TRUE(bit_identical(a.x, b.x) && bit_identical(a.y, b.y) && bit_identical(a.z, b.z));
  EXPECT_TRUE(bit_identical(n1.x, n2.x) && bit_identical(n1.y, n2.y) && bit_identical(n1.z, n2.z));
}

TEST(SpringMassStep, ExplicitChunkLayoutAndRowsGiveTheSameBits) {
  // The CPU runs whole chunks of 32 particles through the sliced layout; without it (chunk_start
  // empty) every particle runs its CSR row. Same sums in the same order: the same bits, cuts included.
  auto fast = explicit_model_from_grid(build_spring_grid_model(test::holed_block_occupancy(9, 8, 6, 2.0),
                                                               test_material(1000, 700, 0.3)));
  cut_explicit_spring(fast, 17);
  auto rows = fast;
  rows.chunk_start.clear();
  ParticleNormals n1, n2;
  const auto a = run_with_threads(fast, 1, &n1), b = run_with_threads(rows, 1, &n2);
  EXPECT_TRUE(bit_identical(a.x, b.x) && bit_identical(a.y, b.y) && bit_identical(a.z, b.z));
  EXPECT_TRUE(bit_identical(n1.x, n2.x) && bit_identical(n1.y, n2.y) && bit_identical(n1.z, n2.z));
  // The cut spring is absent from the layout too: its two entries are no longer present.
  ASSERT_GE(fast.spring_entries[34], 0);
  ASSERT_GE(fast.spring_entries[35], 0);
  EXPECT_EQ(fast.ell_present[fast.spring_entries[34]], 0);
  EXPECT_EQ(fast.ell_present[fast.spring_entries[35]], 0);
}

// The centre of mass of the part below a horizontal cut through a hanging bar.
double lower_centre_z(const SpringGridModel& model, const ParticleState& s, int cut_level) {
  double z = 0, m = 0;
  for (int32_t i = 0; i < s.count(); ++i) {
    const int64_t k = model.cells[i] / (model.lattice.dims[0] * model.lattice.dims[1]);
    if (k <= cut_level) z += s.mass[i] * s.z[i], m += s.mass[i];
  }
  return z / m;
}

TEST(SpringMassStep, ABarCutInTwoSeparates) {
  // A 3 x 3 x 10 bar hanging from its fixed top layer; cut every spring between levels 5 and 6. The
  // lower part then falls freely: its centre of mass moves by Verlet's exact free fall
  // g dt^2 n (n + 1) / 2 (internal forces cancel), while uncut it stays near its rest position.
  const double g = 9810;
  for (bool cut : {false, true}) {
    auto model = build_spring_grid_model(block_occupancy(3, 3, 10, 2.0), test_material(2e4, 1e4));
    auto s = model.make_state();
    const int64_t n = model.particle_count();
    int cut_springs = 0;
    for (int32_t i = 0; i < n; ++i) {
      const int64_t k = model.cells[i] / (model.lattice.dims[0] * model.lattice.dims[1]);
      if (k == 10) s.set_fixed(i, true);
      if (cut && k == 5)
        for (int d = 0; d < kGridDirections; ++d)
          if (kGridDirectionOffsets[d][2] == 1) cut_springs += cut_grid_spring(model, i, d);
    }
    if (cut) {
      EXPECT_EQ(cut_springs, 9 + 24);
    }  // 9 face + 2 * 2 * 3 * 2 edge springs across the level
    StepParameters p;
    p.dt = critical_time_step(model).dt;
    p.gravity = {0, 0, -g};
    const double z0 = lower_centre_z(model, s, 5);
    const int steps = 400;
    for (int q = 0; q < steps; ++q) step(model, s, p);
    const double fall = z0 - lower_centre_z(model, s, 5);
    const double free_fall = g * p.dt * p.dt * steps * (steps + 1) / 2.0;
    if (cut) {
      EXPECT_NEAR(fall, free_fall, 1e-3 * free_fall);
    } else {
      EXPECT_LT(fall, 0.2 * free_fall);
    }
  }
}

TEST(SpringMassStep, ImplicitAndExplicitModelsMoveAlike) {
  // A block standing on its fixed bottom layer, bent sideways by gravity, with spring damping and one
  // cut spring (which must be absent from both models).
  for (bool holes : {false, true}) {
  auto grid = build_spring_grid_model(holes ? test::holed_block_occupancy(8, 7, 5, 2.0) : block_occupancy(8, 7, 5, 2.0),
                                      test_material(1500, 800, 0.2));
  cut_grid_spring(grid, 7, 4);
  const auto expl = explicit_model_from_grid(grid);
  EXPECT_EQ(expl.spring_count(), grid.spring_count());
  auto a = grid.make_state(), b = expl.make_state();
  perturb(a, 0.3), perturb(b, 0.3);
  StepParameters p;
  p.dt = critical_time_step(grid).dt;
  EXPECT_DOUBLE_EQ(p.dt, critical_time_step(expl).dt);
  p.gravity = {0, 9810, 0};
  const int64_t layer = grid.lattice.dims[0] * grid.lattice.dims[1];
  for (int32_t i = 0; i < a.count(); ++i)
    if (grid.cells[i] / layer == 1) a.set_fixed(i, true), b.set_fixed(i, true);
  ParticleNormals na, nb;
  for (int n = 0; n < 1000; ++n) step(grid, a, p, &na), step(expl, b, p, &nb);
  EXPECT_GT(max_abs_difference(a, grid.make_state()), 0.1);
  // Same springs summed in another order: the models differ by float rounding only, ~1e-7 of each
  // force per step, which this damped, anchored motion keeps below ~1e-4 mm (25 ulp at 40 mm). (A
  // free, swinging body would amplify it: that is the dynamics, not the models.)
  EXPECT_LT(max_abs_difference(a, b), 2e-4);
  for (int32_t i = 0; i < a.count(); ++i)
    EXPECT_NEAR(na.x[i] * nb.x[i] + na.y[i] * nb.y[i] + na.z[i] * nb.z[i],
                na.x[i] * na.x[i] + na.y[i] * na.y[i] + na.z[i] * na.z[i], 1e-3);
  }
}

TEST(SpringMassStep, FixedParticlesStayAndZeroLengthSpringsGiveNoNaN) {
  // Two particles at the same place joined by a spring with rest length 1: no direction, no force.
  const std::vector<Real> rest{0, 0, 0, 0, 0, 0, 5, 0, 0};
  const auto model = build_explicit_spring_model(rest, {1, 1, 1}, {{0, 1, 100, 1.0, 0.5}, {1, 2, 100, 5.0, 0}});
  auto s = model.make_state();
  s.set_fixed(2, true);
  StepParameters p;
  p.dt = 1e-3;
  p.gravity = {0, 0, -1000};
  ParticleNormals normals;
  step(model, s, p, &normals);
  EXPECT_TRUE(step_all_finite(s));
  EXPECT_FLOAT_EQ(s.x[0], 0);
  EXPECT_FLOAT_EQ(s.z[0], -1000 * 1e-6);
  EXPECT_EQ(s.x[2], 5);
  EXPECT_EQ(s.z[2], 0);
  for (Real v : normals.x) EXPECT_TRUE(std::isfinite(v));
}

TEST(SpringMassStep, NormalsOnABlockPointOutward) {
  // 5 x 5 x 5 block, stretched by 20 % along x and sheared (the normals must not need the rest shape).
  for (bool deformed : {false, true}) {
    const auto model = build_spring_grid_model(block_occupancy(5, 5, 5, 2.0), test_material());
    auto s = model.make_state();
    if (deformed)
      for (int32_t i = 0; i < s.count(); ++i) s.x[i] = s.px[i] = 1.2f * s.x[i] + 0.1f * s.z[i];
    ParticleNormals n;
    StepParameters p;
    p.dt = 1e-6;
    step(model, s, p, &n);
    for (int k = 1; k <= 5; ++k)
      for (int j = 1; j <= 5; ++j)
        for (int i = 1; i <= 5; ++i) {
          const int32_t q = model.particle_at(i, j, k);
          // Expected direction: outward along each axis where the particle is on the block's boundary.
          const double e[3] = {double(i == 5) - double(i == 1), double(j == 5) - double(j == 1), double(k == 5) - double(k == 1)};
          const double len = std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
          const double dot = n.x[q] * e[0] + n.y[q] * e[1] + n.z[q] * e[2];
          if (len == 0) {
            EXPECT_EQ(std::abs(n.x[q]) + std::abs(n.y[q]) + std::abs(n.z[q]), 0) << q;  // interior: no direction
          } else if (!deformed) {
            EXPECT_NEAR(dot / len, 1.0, 1e-5) << i << " " << j << " " << k;  // exactly the face/edge/corner normal
          } else {
            EXPECT_GT(dot / len, 0.5) << i << " " << j << " " << k;  // outward
          }
        }
  }
}

TEST(SpringMassStep, BadParametersAndAMismatchedStateAreRefused) {
  const auto model = build_spring_grid_model(block_occupancy(2, 2, 2, 1.0), test_material());
  auto s = model.make_state();
  StepParameters p;
  p.dt = 0;
  EXPECT_THROW(step(model, s, p), InputError);
  p.dt = 1e-4;
  auto other = build_spring_grid_model(block_occupancy(3, 2, 2, 1.0), test_material()).make_state();
  EXPECT_THROW(step(model, other, p), InputError);
}

}  // namespace
}  // namespace ctsurg::sim
