// Internal helpers shared by the scenario runners (scenario_run.cpp: spring models;
// fem_scenario_run.cpp: FEM): the tissue's bounding box, tool paths resolved to the simulation's frame,
// surface measures, and the FEM runner's entry point.
#pragma once

#include "ctsurg/core/error.h"
#include "ctsurg/core/tet_mesh_file.h"
#include "ctsurg/core/trajectory_file.h"
#include "ctsurg/sim/base/fixed_regions.h"
#include "ctsurg/sim/scenario/scenario.h"
#include "ctsurg/sim/scenario/scenario_run.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <set>
#include <string>
#include <vector>

namespace ctsurg::sim::detail {

using Vec3 = std::array<double, 3>;

struct Bounds {
  Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  Vec3 at(const Vec3& f) const {
    return {lo[0] + f[0] * (hi[0] - lo[0]), lo[1] + f[1] * (hi[1] - lo[1]), lo[2] + f[2] * (hi[2] - lo[2])};
  }
};

template <typename T>
Bounds bounds_of(const std::vector<T>& p) {
  Bounds b;
  for (size_t i = 0; i < p.size(); i += 3) {
    for (size_t c = 0; c < 3; ++c) {
      b.lo[c] = std::min<double>(b.lo[c], p[i + c]);
      b.hi[c] = std::max<double>(b.hi[c], p[i + c]);
    }
  }
  return b;
}

// A tool's path resolved to LPS mm keyframes; position(t) is piecewise linear, constant outside.
struct ResolvedPath {
  std::vector<double> t;
  std::vector<Vec3> p;
  Vec3 at(double time) const {
    if (time <= t.front()) return p.front();
    if (time >= t.back()) return p.back();
    const size_t k = static_cast<size_t>(std::upper_bound(t.begin(), t.end(), time) - t.begin());
    const double a = (time - t[k - 1]) / (t[k] - t[k - 1]);
    return {p[k - 1][0] + a * (p[k][0] - p[k - 1][0]), p[k - 1][1] + a * (p[k][1] - p[k - 1][1]),
            p[k - 1][2] + a * (p[k][2] - p[k - 1][2])};
  }
};

// In the simulation's frame: LPS minus `origin` (see run_scenario).
template <typename T>
ResolvedPath resolve_path(const ToolAction& tool, const Bounds& bounds, const std::vector<T>& rest, const Vec3& origin,
                          std::string* note) {
  ResolvedPath r;
  for (const auto& k : tool.path) {
    Vec3 p = k.point.value;
    if (k.point.kind == PointSpec::Kind::position_mm) p = {p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]};
    if (k.point.kind == PointSpec::Kind::at_fraction) p = bounds.at(p);
    if (k.point.kind == PointSpec::Kind::offset_mm) p = {r.p.front()[0] + p[0], r.p.front()[1] + p[1], r.p.front()[2] + p[2]};
    r.t.push_back(k.t);
    r.p.push_back(p);
  }
  if (tool.snap_to_tissue) {
    // The nearest rest particle to the first keyframe (lowest id on ties): the whole path moves by the
    // difference, so the tool starts on tissue whatever the bounding box looks like.
    double best = 1e300;
    size_t bi = 0;
    for (size_t i = 0; i < rest.size(); i += 3) {
      const double d = std::pow(rest[i] - r.p[0][0], 2) + std::pow(rest[i + 1] - r.p[0][1], 2) + std::pow(rest[i + 2] - r.p[0][2], 2);
      if (d < best) {
        best = d;
        bi = i;
      }
    }
    const Vec3 shift{rest[bi] - r.p[0][0], rest[bi + 1] - r.p[0][1], rest[bi + 2] - r.p[0][2]};
    for (auto& p : r.p) p = {p[0] + shift[0], p[1] + shift[1], p[2] + shift[2]};
    *note = tool.label + ": path snapped to tissue by " + std::to_string(std::sqrt(best)) + " mm";
  }
  return r;
}

// Enclosed volume (mm^3, divergence theorem) and area (mm^2) of a triangle list over vertices #V x 3.
inline double enclosed_volume(const std::vector<float>& v, const std::vector<uint32_t>& tri) {
  double vol = 0;
  for (size_t f = 0; f < tri.size(); f += 3) {
    const float* a = &v[3 * tri[f]];
    const float* b = &v[3 * tri[f + 1]];
    const float* c = &v[3 * tri[f + 2]];
    vol += (double(a[0]) * (double(b[1]) * c[2] - double(b[2]) * c[1]) - double(a[1]) * (double(b[0]) * c[2] - double(b[2]) * c[0]) +
            double(a[2]) * (double(b[0]) * c[1] - double(b[1]) * c[0])) / 6.0;
  }
  return vol;
}


inline double surface_area(const std::vector<float>& v, const std::vector<uint32_t>& tri) {
  double area = 0;
  for (size_t f = 0; f < tri.size(); f += 3) {
    const float* a = &v[3 * tri[f]];
    const float* b = &v[3 * tri[f + 1]];
    const float* c = &v[3 * tri[f + 2]];
    const double u[3] = {double(b[0]) - a[0], double(b[1]) - a[1], double(b[2]) - a[2]};
    const double w[3] = {double(c[0]) - a[0], double(c[1]) - a[1], double(c[2]) - a[2]};
    const double x = u[1] * w[2] - u[2] * w[1], y = u[2] * w[0] - u[0] * w[2], z = u[0] * w[1] - u[1] * w[0];
    area += 0.5 * std::sqrt(x * x + y * y + z * z);
  }
  return area;
}

// The whole-millimetre point near the middle of a bounding box that a run uses as its local origin.
inline Vec3 local_origin(const Vec3& lo, const Vec3& hi) {
  return {std::round(0.5 * (lo[0] + hi[0])), std::round(0.5 * (lo[1] + hi[1])), std::round(0.5 * (lo[2] + hi[2]))};
}

// The union (increasing ids) of the scenario's fixed regions over the rest positions `rest` (#P x 3,
// the run's local frame: LPS minus `origin`); `by_label` selects a label's particles. InputError
// naming "fixed[r]" when a region selects nothing.
inline std::vector<int32_t> fixed_particles(const Scenario& s, const std::vector<Real>& rest, const Bounds& bounds,
                                            const Vec3& origin,
                                            const std::function<std::vector<int32_t>(uint16_t)>& by_label) {
  std::set<int32_t> fixed;
  for (size_t r = 0; r < s.fixed.size(); ++r) {
    const auto& f = s.fixed[r];
    std::vector<int32_t> ids;
    switch (f.kind) {
      case FixedRegionSpec::Kind::box: {
        Box local = f.box;
        for (size_t c = 0; c < 3; ++c) local.min[c] -= origin[c], local.max[c] -= origin[c];
        ids = particles_in_box(rest, local);
        break;
      }
      case FixedRegionSpec::Kind::box_fraction: ids = particles_in_box(rest, {bounds.at(f.box.min), bounds.at(f.box.max)}); break;
      case FixedRegionSpec::Kind::half_space: {
        HalfSpace local = f.half_space;
        for (size_t c = 0; c < 3; ++c) local.point[c] -= origin[c];
        ids = particles_in_half_space(rest, local);
        break;
      }
      case FixedRegionSpec::Kind::label: ids = by_label(f.label); break;
    }
    if (ids.empty()) throw InputError(s.file.string(), "fixed[" + std::to_string(r) + "]", "selects no particle or node of the model");
    fixed.insert(ids.begin(), ids.end());
  }
  return {fixed.begin(), fixed.end()};
}

// scenario.model == fem (fem_scenario_run.cpp).
Trajectory run_fem_scenario(const Scenario& scenario, RunReport* report, const std::function<void(double)>& progress);

}  // namespace ctsurg::sim::detail
