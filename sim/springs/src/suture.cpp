#include "ctsurg/sim/springs/suture.h"

#include "ctsurg/core/error.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace ctsurg::sim {
namespace {

std::string mm(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g mm", v);
  return text;
}

// The particle nearest to p at rest (#P x 3; lowest id on ties) and its distance.
int32_t nearest_particle(const std::vector<Real>& rest, const Vec3& p, double& distance) {
  double best = std::numeric_limits<double>::infinity();
  int32_t arg = -1;
  for (size_t k = 0; 3 * k + 2 < rest.size(); ++k) {
    const double d = std::pow(rest[3 * k] - p[0], 2) + std::pow(rest[3 * k + 1] - p[1], 2) + std::pow(rest[3 * k + 2] - p[2], 2);
    if (d < best) {
      best = d;
      arg = static_cast<int32_t>(k);
    }
  }
  distance = std::sqrt(best);
  return arg;
}

}  // namespace

double stitch_rest_length(double initial_mm, double target_mm, double start_s, double end_s, double t) {
  const double a = std::clamp((t - start_s) / (end_s - start_s), 0.0, 1.0);
  return initial_mm + (target_mm - initial_mm) * a;
}

std::vector<Stitch> attach_stitches(const std::vector<std::array<Vec3, 2>>& points, const std::vector<std::string>& fields,
                                    const std::vector<Real>& rest, const ParticleState& state, double max_snap_mm,
                                    const std::string& where) {
  if (fields.size() != points.size()) throw InputError(where, "stitches", "one field name per stitch expected");
  if (state.count() == 0 || rest.size() != 3 * static_cast<size_t>(state.count())) {
    throw InputError(where, "stitches", "the model has no particle to stitch, or its rest positions do not match its state");
  }
  std::vector<Stitch> out;
  for (size_t k = 0; k < points.size(); ++k) {
    Stitch st;
    int32_t* ends[2] = {&st.a, &st.b};
    Vec3* offsets[2] = {&st.offset_a, &st.offset_b};
    for (size_t e = 0; e < 2; ++e) {
      const Vec3& p = points[k][e];
      double d = 0;
      *ends[e] = nearest_particle(rest, p, d);
      if (d > max_snap_mm) {
        throw InputError(where, fields[k] + (e == 0 ? ".a" : ".b"),
                         "is " + mm(d) + " from the nearest particle of the tissue (at most " + mm(max_snap_mm) +
                             ", a few cells): put the stitch's point on the tissue's surface");
      }
      const size_t i = static_cast<size_t>(*ends[e]);
      *offsets[e] = {p[0] - rest[3 * i], p[1] - rest[3 * i + 1], p[2] - rest[3 * i + 2]};
    }
    if (st.a == st.b) {
      throw InputError(where, fields[k], "both ends attach to the same particle (" + std::to_string(st.a) +
                                             "): put a and b on the two lips, more than a cell apart");
    }
    const size_t a = static_cast<size_t>(st.a), b = static_cast<size_t>(st.b);
    st.initial_length = std::sqrt(std::pow(double(state.x[b]) - state.x[a], 2) + std::pow(double(state.y[b]) - state.y[a], 2) +
                                  std::pow(double(state.z[b]) - state.z[a], 2));
    if (st.initial_length > kMaxStitchLengthMm) {
      throw InputError(where, fields[k], "its ends attach to particles " + mm(st.initial_length) + " apart (at most " +
                                             mm(kMaxStitchLengthMm) + "): a stitch joins the two lips of one incision");
    }
    out.push_back(st);
  }
  return out;
}

double stitch_step_limit(double mass, double spring_sum, double stitch_stiffness) {
  if (!(mass > 0)) return std::numeric_limits<double>::infinity();
  return std::sqrt(2.0) * std::sqrt(mass / (spring_sum + stitch_stiffness));
}

double apply_stitches(ParticleState& s, const std::vector<Stitch>& stitches, const SutureSchedule& schedule, double t, double dt) {
  double worst = 0;
  for (const Stitch& st : stitches) {
    const double rest_mm = stitch_rest_length(st.initial_length, schedule.target_mm, schedule.start_s, schedule.end_s, t);
    const size_t a = static_cast<size_t>(st.a), b = static_cast<size_t>(st.b);
    const double d[3] = {double(s.x[b]) - s.x[a], double(s.y[b]) - s.y[a], double(s.z[b]) - s.z[a]};
    const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (!(len > 0)) continue;  // coincident ends: no direction, no force (never NaN)
    worst = std::max(worst, std::abs(len - rest_mm));
    const double f = schedule.stiffness * (len - rest_mm) / len;  // times d: the force on a, uN
    const double ka = f * s.inv_mass[a] * dt * dt, kb = f * s.inv_mass[b] * dt * dt;
    s.x[a] += static_cast<Real>(ka * d[0]);
    s.y[a] += static_cast<Real>(ka * d[1]);
    s.z[a] += static_cast<Real>(ka * d[2]);
    s.x[b] -= static_cast<Real>(kb * d[0]);
    s.y[b] -= static_cast<Real>(kb * d[1]);
    s.z[b] -= static_cast<Real>(kb * d[2]);
  }
  return worst;
}

}  // namespace ctsurg::sim
