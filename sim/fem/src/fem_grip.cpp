#include "ctsurg/sim/fem/fem_grip.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/fem/kernels/fem_quadratic_element_impl.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace ctsurg::sim {
namespace {

constexpr const char* kGripWhere = "fem grip";
constexpr int kMaxGripDepth = 7;  // 8^7 pieces at most per element (the band is resolved long before)
constexpr int kBandPoints = 2;    // per direction, in a piece the band crosses
constexpr double kBandPiece = 0.5;  // a piece the band crosses is split while its radius exceeds this x the band's width

// A collapsed (Duffy) Gauss-Legendre product rule on the unit tetrahedron: barycentric points and
// weights summing to 1. With n points per direction it integrates polynomials of degree 2n - 3 exactly
// (the collapse adds degree 2 in the first direction).
struct TetRule {
  std::vector<std::array<double, 4>> points;
  std::vector<double> weights;
};

TetRule duffy_rule(int n) {
  std::vector<double> x, w;
  if (n == 2) {
    x = {-1 / std::sqrt(3.0), 1 / std::sqrt(3.0)};
    w = {1, 1};
  } else if (n == 3) {
    const double a = std::sqrt(0.6);
    x = {-a, 0, a};
    w = {5.0 / 9, 8.0 / 9, 5.0 / 9};
  } else {
    x = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526};
    w = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538};
  }
  TetRule rule;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const double s = (1 + x[i]) / 2, t = (1 + x[j]) / 2, v = (1 + x[k]) / 2;
        const double l1 = s, l2 = (1 - s) * t, l3 = (1 - s) * (1 - t) * v;
        rule.points.push_back({1 - l1 - l2 - l3, l1, l2, l3});
        rule.weights.push_back(6 * (1 - s) * (1 - s) * (1 - t) * (w[i] / 2) * (w[j] / 2) * (w[k] / 2));
      }
  return rule;
}

const TetRule& inner_rule() {
  static const TetRule rule = duffy_rule(4);
  return rule;
}
const TetRule& band_rule() {
  static const TetRule rule = duffy_rule(kBandPoints);
  return rule;
}

void shape(int order, const double* l, double* N) {
  if (order == 2) {
    fem_quadratic_shape(l, N);
  } else {
    for (int a = 0; a < 4; ++a) N[a] = l[a];
  }
}

// One element's integration: its nodes' capture positions and the sphere.
struct ElementIntegral {
  int order = 1, npe = 4;
  double x[30];              // the element's nodes at the capture, mm
  std::array<double, 3> centre{};
  double inner = 0, outer = 0, edge = 1;
  double volume = 0;         // the element's rest volume, mm^3
  double m[100] = {};        // integral of w N_a N_b, mm^3
  double held = 0;           // integral of w, mm^3

  void position(const double* l, double* p) const {
    double N[10];
    shape(order, l, N);
    p[0] = p[1] = p[2] = 0;
    for (int a = 0; a < npe; ++a)
      for (int c = 0; c < 3; ++c) p[c] += N[a] * x[3 * a + c];
  }
  double weight(double d) const {  // 1 inside, 0 outside, a smoothstep over the band
    if (d <= inner) return 1;
    if (d >= outer) return 0;
    const double t = (d - inner) / edge;
    return 1 - t * t * (3 - 2 * t);
  }
  double distance(const double* p) const {
    return std::sqrt((p[0] - centre[0]) * (p[0] - centre[0]) + (p[1] - centre[1]) * (p[1] - centre[1]) +
                     (p[2] - centre[2]) * (p[2] - centre[2]));
  }
  void apply(const TetRule& rule, const double (*corners)[4], double fraction, bool whole) {
    double N[10];
    for (std::size_t q = 0; q < rule.points.size(); ++q) {
      double l[4] = {0, 0, 0, 0};
      for (int k = 0; k < 4; ++k)
        for (int c = 0; c < 4; ++c) l[c] += rule.points[q][k] * corners[k][c];
      double w = 1;
      if (!whole) {
        double p[3];
        position(l, p);
        w = weight(distance(p));
        if (w == 0) continue;
      }
      const double f = volume * fraction * rule.weights[q] * w;
      shape(order, l, N);
      held += f;
      for (int a = 0; a < npe; ++a)
        for (int b = 0; b < npe; ++b) m[npe * a + b] += f * N[a] * N[b];
    }
  }
  // The piece with barycentric corners `corners` (4 x 4) and this fraction of the element's volume.
  void integrate(const double (*corners)[4], double fraction, int depth) {
    double p[4][3], mid[3] = {0, 0, 0};
    for (int k = 0; k < 4; ++k) {
      position(corners[k], p[k]);
      for (int c = 0; c < 3; ++c) mid[c] += p[k][c] / 4;
    }
    double radius = 0;
    for (int k = 0; k < 4; ++k)
      radius = std::max(radius, std::sqrt((p[k][0] - mid[0]) * (p[k][0] - mid[0]) + (p[k][1] - mid[1]) * (p[k][1] - mid[1]) +
                                          (p[k][2] - mid[2]) * (p[k][2] - mid[2])));
    if (order == 2) radius *= 1.25;  // a quadratic map bulges past its corners' sphere
    const double d = distance(mid);
    if (d - radius >= outer) return;
    if (d + radius <= inner) {
      apply(inner_rule(), corners, fraction, true);
      return;
    }
    if (depth < kMaxGripDepth && radius > kBandPiece * edge) {
      // Eight children by the edge midpoints (Bey's red refinement: equal volumes).
      double e[10][4];
      for (int k = 0; k < 4; ++k)
        for (int c = 0; c < 4; ++c) e[k][c] = corners[k][c];
      const int ends[6][2] = {{0, 1}, {1, 2}, {0, 2}, {0, 3}, {1, 3}, {2, 3}};
      for (int k = 0; k < 6; ++k)
        for (int c = 0; c < 4; ++c) e[4 + k][c] = (corners[ends[k][0]][c] + corners[ends[k][1]][c]) / 2;
      // 01 = 4, 12 = 5, 02 = 6, 03 = 7, 13 = 8, 23 = 9
      const int children[8][4] = {{0, 4, 6, 7}, {4, 1, 5, 8}, {6, 5, 2, 9}, {7, 8, 9, 3},
                                  {4, 6, 7, 8}, {4, 6, 5, 8}, {6, 7, 8, 9}, {6, 5, 8, 9}};
      for (const auto& child : children) {
        double cc[4][4];
        for (int k = 0; k < 4; ++k)
          for (int c = 0; c < 4; ++c) cc[k][c] = e[child[k]][c];
        integrate(cc, fraction / 8, depth + 1);
      }
      return;
    }
    apply(band_rule(), corners, fraction, false);
  }
};

}  // namespace

FemGrip fem_capture_grip(const FemModel& model, const std::vector<double>& u, const std::array<double, 3>& centre, double radius,
                         double edge, double stiffness) {
  const int32_t nn = model.node_count(), npe = model.nodes_per_element();
  if (u.size() != 3 * static_cast<std::size_t>(nn)) throw InputError(kGripWhere, "displacements", "expected #N x 3 values");
  if (!(std::isfinite(radius) && radius > 0)) throw InputError(kGripWhere, "radius_mm", "must be finite and > 0");
  if (!(std::isfinite(edge) && edge > 0 && edge <= radius)) throw InputError(kGripWhere, "edge_mm", "must be in (0, radius]");
  if (!(std::isfinite(stiffness) && stiffness > 0)) throw InputError(kGripWhere, "stiffness", "must be finite and > 0");
  for (double c : centre)
    if (!std::isfinite(c)) throw InputError(kGripWhere, "centre", "must be finite");
  FemGrip grip;
  ElementIntegral in;
  in.order = model.order;
  in.npe = npe;
  in.centre = centre;
  in.inner = radius - edge / 2;
  in.outer = radius + edge / 2;
  in.edge = edge;
  const double unit[4][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};
  std::vector<double> matrices;
  for (int32_t e = 0; e < model.tet_count(); ++e) {
    const int32_t* v = &model.tets[static_cast<std::size_t>(npe) * e];
    double lo = HUGE_VAL;
    for (int a = 0; a < npe; ++a) {
      for (int c = 0; c < 3; ++c) in.x[3 * a + c] = model.nodes[3 * v[a] + c] + u[3 * static_cast<std::size_t>(v[a]) + c];
      lo = std::min(lo, in.distance(&in.x[3 * a]));
    }
    // An element whose nodes are all far outside cannot reach the sphere (its diameter bounds the gap).
    double diameter = 0;
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b)
        diameter = std::max(diameter, std::hypot(in.x[3 * a] - in.x[3 * b], in.x[3 * a + 1] - in.x[3 * b + 1], in.x[3 * a + 2] - in.x[3 * b + 2]));
    if (lo - 1.25 * diameter >= in.outer) continue;
    in.volume = model.rest_volume[static_cast<std::size_t>(e)];
    std::fill(std::begin(in.m), std::end(in.m), 0.0);
    in.held = 0;
    in.integrate(unit, 1.0, 0);
    if (!(in.held > 0)) continue;
    grip.elements.push_back(e);
    grip.volume_mm3 += in.held;
    for (int k = 0; k < npe * npe; ++k) matrices.push_back(stiffness * in.m[k]);
    for (int a = 0; a < npe; ++a) grip.nodes.push_back(v[a]);
  }
  grip.matrices = std::move(matrices);
  std::sort(grip.nodes.begin(), grip.nodes.end());
  grip.nodes.erase(std::unique(grip.nodes.begin(), grip.nodes.end()), grip.nodes.end());
  for (const int32_t e : grip.elements)
    for (int a = 0; a < npe; ++a) {
      const int32_t n = model.tets[static_cast<std::size_t>(npe) * e + a];
      grip.element_nodes.push_back(static_cast<int32_t>(std::lower_bound(grip.nodes.begin(), grip.nodes.end(), n) - grip.nodes.begin()));
    }
  for (const int32_t n : grip.nodes)
    for (int c = 0; c < 3; ++c) grip.captured.push_back(u[3 * static_cast<std::size_t>(n) + c]);
  grip.target = grip.captured;
  return grip;
}

void fem_grip_move(FemGrip& grip, const std::array<double, 3>& travel) {
  grip.target.resize(grip.captured.size());
  for (std::size_t k = 0; k < grip.captured.size(); ++k) grip.target[k] = grip.captured[k] + travel[k % 3];
}

namespace {

// For each element of the grip: z = P_e (u - s g) on its nodes, handed to `use(node, axis, z, (u - s g) there)`.
template <class Use>
void for_grip_products(const FemModel& model, const FemGrip& grip, const double* u, double s, Use use) {
  const int npe = model.nodes_per_element();
  for (std::size_t k = 0; k < grip.elements.size(); ++k) {
    const int32_t* local = &grip.element_nodes[static_cast<std::size_t>(npe) * k];
    const double* m = &grip.matrices[static_cast<std::size_t>(npe * npe) * k];
    double w[30];
    for (int a = 0; a < npe; ++a) {
      const int32_t n = grip.nodes[static_cast<std::size_t>(local[a])];
      for (int c = 0; c < 3; ++c) w[3 * a + c] = u[3 * static_cast<std::size_t>(n) + c] - s * grip.target[3 * static_cast<std::size_t>(local[a]) + c];
    }
    for (int a = 0; a < npe; ++a) {
      double z[3] = {0, 0, 0};
      for (int b = 0; b < npe; ++b)
        for (int c = 0; c < 3; ++c) z[c] += m[npe * a + b] * w[3 * b + c];
      const int32_t n = grip.nodes[static_cast<std::size_t>(local[a])];
      for (int c = 0; c < 3; ++c) use(n, c, z[c], w[3 * a + c]);
    }
  }
}

}  // namespace

void fem_grip_add_forces(const FemModel& model, const FemGrip& grip, const double* u, double s, double* f) {
  for_grip_products(model, grip, u, s, [&](int32_t n, int c, double z, double) { f[3 * static_cast<std::size_t>(n) + c] -= z; });
}

double fem_grip_energy(const FemModel& model, const FemGrip& grip, const double* u, double s) {
  double e = 0;
  for_grip_products(model, grip, u, s, [&](int32_t, int, double z, double w) { e += 0.5 * w * z; });
  return e;
}

void fem_grip_add_product(const FemModel& model, const FemGrip& grip, const double* v, double* out) {
  // P v is P (v - s g) at s = 0.
  for_grip_products(model, grip, v, 0.0, [&](int32_t n, int c, double z, double) { out[3 * static_cast<std::size_t>(n) + c] += z; });
}

std::array<double, 6> fem_grip_load(const FemModel& model, const FemGrip& grip, const std::vector<double>& u,
                                    const std::array<double, 3>& about) {
  std::vector<double> f(u.size(), 0.0);
  fem_grip_add_forces(model, grip, u.data(), 1.0, f.data());
  return fem_nodal_load(model, grip.nodes, u, f, about);
}

std::array<double, 6> fem_nodal_load(const FemModel& model, const std::vector<int32_t>& nodes, const std::vector<double>& u,
                                     const std::vector<double>& f, const std::array<double, 3>& about) {
  std::array<double, 6> load{0, 0, 0, 0, 0, 0};
  for (const int32_t n : nodes) {
    const std::size_t i = 3 * static_cast<std::size_t>(n);
    const double r[3] = {model.nodes[i] + u[i] - about[0], model.nodes[i + 1] + u[i + 1] - about[1], model.nodes[i + 2] + u[i + 2] - about[2]};
    const double* fn = &f[i];
    load[0] += fn[0];
    load[1] += fn[1];
    load[2] += fn[2];
    load[3] += r[1] * fn[2] - r[2] * fn[1];
    load[4] += r[2] * fn[0] - r[0] * fn[2];
    load[5] += r[0] * fn[1] - r[1] * fn[0];
  }
  for (double& v : load) v *= 1e-6;  // uN -> N, uN mm -> N mm
  return load;
}

}  // namespace ctsurg::sim
