// Tests of the sparse Cholesky factor (src/sparse_cholesky.h, an internal header of sim/fem): the
// single-precision substitutions (make_single, solve_single: inverted diagonal blocks, two subtrees of
// the elimination tree at once) solve the system to float's precision, give the same bits on one
// thread as on several, and are refused without make_single(); a matrix that is not positive definite
// names its column.
#include "sparse_cholesky.h"

#include "ctsurg/core/error.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace ctsurg::sim {
namespace {

// The 7-point Laplacian of an nx x ny x nz grid (Dirichlet outside) plus `shift` on the diagonal, as
// compressed rows of both triangles, sorted: symmetric positive definite for shift >= 0 (the diagonal
// 6.2 at least covers the stencil's largest eigenvalue, 2 (1 + 1 + 1.1)), with a
// nested-dissection elimination tree of many supernodes.
struct Csr {
  int32_t n = 0;
  std::vector<int32_t> outer, inner;
  std::vector<double> values;
};

Csr grid_laplacian(int nx, int ny, int nz, double shift) {
  Csr a;
  a.n = nx * ny * nz;
  a.outer.push_back(0);
  const auto id = [&](int i, int j, int k) { return i + nx * (j + ny * k); };
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const std::array<std::array<int, 3>, 7> stencil{{{0, 0, -1}, {0, -1, 0}, {-1, 0, 0}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
        std::vector<std::pair<int32_t, double>> row;
        for (const auto& d : stencil) {
          const int ii = i + d[0], jj = j + d[1], kk = k + d[2];
          if (ii < 0 || jj < 0 || kk < 0 || ii >= nx || jj >= ny || kk >= nz) continue;
          const bool self = d[0] == 0 && d[1] == 0 && d[2] == 0;
          // A little anisotropy and variation, so the factor is not a pattern of equal numbers.
          row.emplace_back(id(ii, jj, kk), self ? 6.2 + shift + 0.01 * (i % 3) : -1.0 - 0.1 * (d[2] != 0));
        }
        std::sort(row.begin(), row.end());
        for (const auto& [c, v] : row) {
          a.inner.push_back(c);
          a.values.push_back(v);
        }
        a.outer.push_back(static_cast<int32_t>(a.inner.size()));
      }
  return a;
}

std::vector<double> multiply(const Csr& a, const std::vector<double>& x) {
  std::vector<double> y(static_cast<size_t>(a.n), 0.0);
  for (int32_t r = 0; r < a.n; ++r)
    for (int32_t p = a.outer[r]; p < a.outer[r + 1]; ++p) y[static_cast<size_t>(r)] += a.values[static_cast<size_t>(p)] * x[static_cast<size_t>(a.inner[p])];
  return y;
}

double largest_magnitude(const std::vector<double>& v) {
  double m = 0;
  for (double x : v) m = std::max(m, std::abs(x));
  return m;
}

TEST(SparseCholesky, SinglePrecisionSubstitutionsSolveToFloatPrecision) {
  const Csr a = grid_laplacian(18, 16, 14, 0.05);  // 4,032 unknowns
  SparseCholesky chol("test");
  chol.analyze(a.n, a.outer.data(), a.inner.data());
  ASSERT_EQ(chol.factorize(a.values.data()), -1);
  chol.make_single();
  ASSERT_TRUE(chol.has_single());
  std::vector<double> x_true(static_cast<size_t>(a.n));
  for (size_t i = 0; i < x_true.size(); ++i) x_true[i] = std::sin(0.37 * static_cast<double>(i)) + 0.5;
  const std::vector<double> b = multiply(a, x_true);
  std::vector<double> x_double(b.size()), x_single(b.size());
  chol.solve(b.data(), x_double.data());
  chol.solve_single(b.data(), x_single.data(), 2);
  std::vector<double> e_double(b.size()), e_single(b.size());
  for (size_t i = 0; i < b.size(); ++i) {
    e_double[i] = x_double[i] - x_true[i];
    e_single[i] = x_single[i] - x_true[i];
  }
  EXPECT_LT(largest_magnitude(e_double), 1e-10 * largest_magnitude(x_true));
  // Float's precision times the conditioning (about 120 here): well under 1e-4, far from the 1e-7 that
  // only exact double substitutions reach.
  EXPECT_LT(largest_magnitude(e_single), 1e-4 * largest_magnitude(x_true));
  EXPECT_GT(largest_magnitude(e_single), 1e-9 * largest_magnitude(x_true));
}

TEST(SparseCholesky, SinglePrecisionBitsDoNotDependOnTheThreads) {
  const Csr a = grid_laplacian(20, 20, 20, 0.0);
  SparseCholesky chol("test");
  chol.analyze(a.n, a.outer.data(), a.inner.data());
  ASSERT_EQ(chol.factorize(a.values.data()), -1);
  chol.make_single();
  std::vector<double> b(static_cast<size_t>(a.n));
  for (size_t i = 0; i < b.size(); ++i) b[i] = std::cos(0.11 * static_cast<double>(i));
  std::vector<double> one(b.size()), two(b.size()), eight(b.size());
  chol.solve_single(b.data(), one.data(), 1);
  chol.solve_single(b.data(), two.data(), 2);
  chol.solve_single(b.data(), eight.data(), 8);
  EXPECT_EQ(one, two);
  EXPECT_EQ(one, eight);
  // In place (b and x the same array), as the quasi-Newton iteration's callers may.
  std::vector<double> in_place = b;
  chol.solve_single(in_place.data(), in_place.data(), 2);
  EXPECT_EQ(in_place, one);
}

TEST(SparseCholesky, SinglePrecisionOnADenseMatrixOfOneSupernode) {
  // A small dense SPD matrix: one supernode, no subtrees to split (all of it is the top).
  const int32_t n = 12;
  Csr a;
  a.n = n;
  a.outer.push_back(0);
  for (int32_t r = 0; r < n; ++r) {
    for (int32_t c = 0; c < n; ++c) {
      a.inner.push_back(c);
      a.values.push_back(r == c ? n + 1.0 : 1.0 / (1 + std::abs(r - c)));
    }
    a.outer.push_back(static_cast<int32_t>(a.inner.size()));
  }
  SparseCholesky chol("test");
  chol.analyze(n, a.outer.data(), a.inner.data());
  ASSERT_EQ(chol.factorize(a.values.data()), -1);
  chol.make_single();
  std::vector<double> x_true(static_cast<size_t>(n));
  for (int32_t i = 0; i < n; ++i) x_true[static_cast<size_t>(i)] = i - 5.5;
  const std::vector<double> b = multiply(a, x_true);
  std::vector<double> x(b.size());
  chol.solve_single(b.data(), x.data(), 2);
  for (int32_t i = 0; i < n; ++i) EXPECT_NEAR(x[static_cast<size_t>(i)], x_true[static_cast<size_t>(i)], 1e-5);
}

TEST(SparseCholesky, RefusesWhatItCannotDo) {
  const Csr a = grid_laplacian(4, 4, 4, 0.0);
  SparseCholesky chol("test solver");
  std::vector<double> b(static_cast<size_t>(a.n), 1.0), x(b.size());
  chol.analyze(a.n, a.outer.data(), a.inner.data());
  EXPECT_THROW(chol.make_single(), RuntimeError);  // no factor yet
  ASSERT_EQ(chol.factorize(a.values.data()), -1);
  try {
    chol.solve_single(b.data(), x.data(), 1);
    FAIL() << "solve_single without make_single";
  } catch (const RuntimeError& e) {
    EXPECT_NE(std::string(e.what()).find("test solver"), std::string::npos) << e.what();
  }
  // Not positive definite: the failing column is reported, and the single form goes with the factor.
  chol.make_single();
  Csr bad = a;
  for (int32_t r = 0; r < bad.n; ++r)
    for (int32_t p = bad.outer[r]; p < bad.outer[r + 1]; ++p)
      if (bad.inner[p] == r && r == 40) bad.values[static_cast<size_t>(p)] = -1;
  EXPECT_GE(chol.factorize(bad.values.data()), 0);
  EXPECT_FALSE(chol.has_single());
}

}  // namespace
}  // namespace ctsurg::sim
