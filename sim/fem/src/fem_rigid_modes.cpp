#include "fem_rigid_modes.h"

#include "ctsurg/core/error.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>

namespace ctsurg::sim {

namespace {

std::string vec_text(Eigen::Vector3d v, int precision) {
  for (double& x : v)
    if (std::abs(x) < 0.5 * std::pow(10.0, -precision)) x = 0;  // no "-0.0"
  std::ostringstream s;
  s << std::fixed << std::setprecision(precision) << "(" << v[0] << ", " << v[1] << ", " << v[2] << ")";
  return s.str();
}

std::string direction_text(Eigen::Vector3d d) {
  d.normalize();
  for (int a = 0; a < 3; ++a)
    if (std::abs(std::abs(d[a]) - 1) < 1e-6) return std::string(1, "xyz"[a]);
  return vec_text(d, 3);
}

}  // namespace

// A rigid velocity field v(x) = t + w x (x - c) / diag, named: a translation, or a rotation about an axis
// (the points where v is parallel to w: p = c + diag (w x t) / |w|^2), or a screw of both.
std::string rigid_mode_text(const Eigen::Vector3d& t, const Eigen::Vector3d& w, const Eigen::Vector3d& centre, double diag) {
  const double wn = w.norm(), tn = t.norm();
  if (wn < 1e-6 * std::max(tn, 1e-300)) return "translation along " + direction_text(t);
  const Eigen::Vector3d p = centre + diag * w.cross(t) / (wn * wn);
  const double along = t.dot(w) / wn;  // the translation along the axis: a screw when not 0
  std::string text = "rotation about the axis along " + direction_text(w) + " through " + vec_text(p, 1) + " mm";
  if (std::abs(along) > 1e-6 * std::max(tn, wn)) text += " (with a translation along it)";
  return text;
}

std::vector<std::string> free_rigid_modes(const FemModel& model, const std::vector<uint8_t>& held, double diag, int64_t* held_rows) {
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
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eig(gram);
  const double hi = eig.eigenvalues()[5];
  std::vector<std::string> free_modes;
  for (int k = 0; k < 6; ++k) {
    if (rows > 0 && eig.eigenvalues()[k] > 1e-10 * hi) continue;
    const Eigen::Matrix<double, 6, 1> mode = eig.eigenvectors().col(k);
    const Eigen::Vector3d lps_centre = centre + Eigen::Vector3d(model.frame_origin[0], model.frame_origin[1], model.frame_origin[2]);
    free_modes.push_back(rigid_mode_text(mode.head<3>(), mode.tail<3>(), lps_centre, diag));
  }
  if (held_rows) *held_rows = rows;
  return free_modes;
}

void check_rigid_modes(const FemModel& model, const std::vector<uint8_t>& held, double diag, const char* where) {
  int64_t rows = 0;
  const std::vector<std::string> free_modes = free_rigid_modes(model, held, diag, &rows);
  if (free_modes.empty()) return;
  std::string list;
  for (std::size_t k = 0; k < free_modes.size(); ++k) list += (k ? "; " : "") + free_modes[k];
  throw InputError(where, "boundary conditions",
                   (rows == 0 ? std::string("no fixed node or component") : "the " + std::to_string(rows) + " held components") +
                       " leave " + std::to_string(free_modes.size()) + " rigid motion" + (free_modes.size() > 1 ? "s" : "") +
                       " free (" + list +
                       "): the stiffness matrix is singular; fix or prescribe at least 3 non-collinear nodes, or add "
                       "the components that stop these motions");
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
