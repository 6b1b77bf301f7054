#include "fem_tangent_projection.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <algorithm>

namespace ctsurg::sim::cpu {

bool project_tangent_psd(double* A) {
  using Mat9 = Eigen::Matrix<double, 9, 9, Eigen::RowMajor>;
  Eigen::Map<Mat9> a(A);
  // A semi-definite tangent (the linear law's, or Neo-Hookean's at rest: rotations cost nothing) has
  // zero eigenvalues, where a plain Cholesky attempt fails on rounding; shifted by a hair it succeeds,
  // and only a truly negative eigenvalue sends the element to the eigendecomposition.
  const double shift = 1e-9 * std::max(a.trace() / 9, 1e-300);
  if (Eigen::LLT<Mat9>(a + shift * Mat9::Identity()).info() == Eigen::Success) return false;
  const Eigen::SelfAdjointEigenSolver<Mat9> eig(0.5 * (a + a.transpose()));
  const Eigen::Matrix<double, 9, 1> values = eig.eigenvalues().cwiseMax(0.0);
  a = eig.eigenvectors() * values.asDiagonal() * eig.eigenvectors().transpose();
  return true;
}

}  // namespace ctsurg::sim::cpu
