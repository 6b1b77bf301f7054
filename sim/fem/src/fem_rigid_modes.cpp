#include "fem_rigid_modes.h"

#include "ctsurg/core/error.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <string>

namespace ctsurg::sim {

void check_rigid_modes(const FemModel& model, const std::vector<uint8_t>& held, double diag, const char* where) {
  const int32_t n = model.node_count();
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (int32_t i = 0; i < n; ++i) centre += Eigen::Vector3d(model.nodes[3 * i], model.nodes[3 * i + 1], model.nodes[3 * i + 2]);
  centre /= n;
  Eigen::Matrix<double, 6, 6> gram = Eigen::Matrix<double, 6, 6>::Zero();
  int64_t rows = 0;
  for (int32_t i = 0; i < n; ++i) {
    if (model.node_offsets[i + 1] == model.node_offsets[i]) continue;  // unused: no stiffness at all
    const Eigen::Vector3d x = (Eigen::Vector3d(model.nodes[3 * i], model.nodes[3 * i + 1], model.nodes[3 * i + 2]) - centre) / diag;
    for (int a = 0; a < 3; ++a) {
      if (!held[3 * i + a]) continue;
      Eigen::Matrix<double, 6, 1> r = Eigen::Matrix<double, 6, 1>::Zero();
      r[a] = 1;
      const Eigen::Vector3d ea = Eigen::Vector3d::Unit(a);
      for (int w = 0; w < 3; ++w) r[3 + w] = Eigen::Vector3d::Unit(w).cross(x).dot(ea);  // (omega x x)_a
      gram += r * r.transpose();
      ++rows;
    }
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eig(gram, Eigen::EigenvaluesOnly);
  const double lo = eig.eigenvalues()[0], hi = eig.eigenvalues()[5];
  if (rows == 0 || !(lo > 1e-10 * hi))
    throw InputError(where, "boundary conditions",
                     rows == 0 ? "no fixed node or component: the stiffness matrix is singular (rigid motions are free); "
                                 "fix or prescribe at least 3 non-collinear nodes"
                               : "the " + std::to_string(rows) +
                                     " held components leave a rigid motion free (the stiffness matrix is singular); fix or "
                                     "prescribe at least 3 non-collinear nodes");
}

double fem_bounding_diagonal(const FemModel& model) {
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (int32_t i = 0; i < model.node_count(); ++i)
    for (int c = 0; c < 3; ++c) {
      lo[c] = std::min(lo[c], model.nodes[3 * i + c]);
      hi[c] = std::max(hi[c], model.nodes[3 * i + c]);
    }
  return std::sqrt(std::pow(hi[0] - lo[0], 2) + std::pow(hi[1] - lo[1], 2) + std::pow(hi[2] - lo[2], 2));
}

}  // namespace ctsurg::sim
