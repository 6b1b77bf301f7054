#include "ctsurg/sim/vessel/vessel_skinning.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/vessel/vessel_frames.h"
#include "vessel_math.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace ctsurg::sim {
namespace {

// The pieces of branch b: [k0, k1] ring ranges (indices within the branch) joined by alive segments.
template <typename F>
void for_each_piece(const VesselChain& ch, const std::vector<uint8_t>& alive, int32_t b, F&& f) {
  const int64_t n = ch.branch_offsets[static_cast<size_t>(b) + 1] - ch.branch_offsets[static_cast<size_t>(b)];
  const int32_t s0 = ch.branch_first_segment[static_cast<size_t>(b)];
  int64_t start = 0;
  for (int64_t k = 0; k + 1 < n; ++k) {
    if (!alive[static_cast<size_t>(s0 + k)]) {
      f(start, k);
      start = k + 1;
    }
  }
  f(start, n - 1);
}

}  // namespace

VesselSkin::VesselSkin(const VesselChain& chain, int spokes, VesselSkinning mode) : chain_(chain), spokes_(spokes), mode_(mode) {
  if (spokes < 3 || spokes > 1024) throw InputError("vessel", "vessel.spokes", "must be in [3, 1024]");
  update_topology(std::vector<uint8_t>(static_cast<size_t>(chain.segment_count()), 1));
}

void VesselSkin::update_topology(const std::vector<uint8_t>& alive) {
  alive_ = alive;
  triangles_.clear();
  std::vector<uint32_t> caps;
  const uint32_t m = static_cast<uint32_t>(spokes_);
  for (int32_t b = 0; b < chain_.branch_count(); ++b) {
    const uint32_t g0 = static_cast<uint32_t>(chain_.branch_offsets[static_cast<size_t>(b)]);
    for_each_piece(chain_, alive_, b, [&](int64_t k0, int64_t k1) {
      if (k1 == k0) return;  // a ring alone
      for (int64_t k = k0; k < k1; ++k) {
        const uint32_t a = (g0 + static_cast<uint32_t>(k)) * m, c = a + m;
        for (uint32_t j = 0; j < m; ++j) {
          const uint32_t jn = (j + 1) % m;
          triangles_.insert(triangles_.end(), {a + j, a + jn, c + j, a + jn, c + jn, c + j});
        }
      }
      const uint32_t first = (g0 + static_cast<uint32_t>(k0)) * m, last = (g0 + static_cast<uint32_t>(k1)) * m;
      for (uint32_t j = 1; j + 1 < m; ++j) {
        caps.insert(caps.end(), {first, first + j + 1, first + j});
        caps.insert(caps.end(), {last, last + j, last + j + 1});
      }
    });
  }
  caps_ = static_cast<int64_t>(caps.size() / 3);
  triangles_.insert(triangles_.end(), caps.begin(), caps.end());
}

void VesselSkin::vertices(const std::vector<double>& x, const std::vector<Quaternion>* frames, std::vector<float>& out,
                          std::vector<double>* first_spokes) const {
  const size_t m = static_cast<size_t>(spokes_);
  out.resize(3 * m * chain_.branch_atoms.size());
  if (first_spokes) first_spokes->assign(3 * chain_.branch_atoms.size(), 0.0);
  std::vector<double> cos_t(m), sin_t(m);
  for (size_t j = 0; j < m; ++j) {
    cos_t[j] = std::cos(2 * std::numbers::pi * static_cast<double>(j) / static_cast<double>(m));
    sin_t[j] = std::sin(2 * std::numbers::pi * static_cast<double>(j) / static_cast<double>(m));
  }
  std::vector<double> pts, tan, nrm;
  for (int32_t b = 0; b < chain_.branch_count(); ++b) {
    const int64_t g0 = chain_.branch_offsets[static_cast<size_t>(b)];
    const int32_t s0 = chain_.branch_first_segment[static_cast<size_t>(b)];
    for_each_piece(chain_, alive_, b, [&](int64_t k0, int64_t k1) {
      const size_t n = static_cast<size_t>(k1 - k0 + 1);
      pts.resize(3 * n);
      tan.resize(3 * n);
      nrm.resize(3 * n);
      for (size_t i = 0; i < n; ++i) {
        const size_t atom = static_cast<size_t>(chain_.branch_atoms[static_cast<size_t>(g0 + k0) + i]);
        for (size_t c = 0; c < 3; ++c) pts[3 * i + c] = x[3 * atom + c];
      }
      if (n == 1) {
        // A ring alone: the axis of the segment it had (or x).
        tan[0] = 1, tan[1] = 0, tan[2] = 0;
      } else {
        polyline_tangents(pts.data(), n, tan.data());
      }
      if (mode_ == VesselSkinning::rmf) {
        const V3 t0 = at(tan, 0);
        const Vec3 s = plane_spoke({t0.x(), t0.y(), t0.z()});
        rotation_minimizing_normals(pts.data(), tan.data(), n, s, nrm.data());
        if (frames) {
          // The chain's frames: the mean d1 of the ring's segments in this piece, across its axis.
          for (size_t i = 0; i < n; ++i) {
            const int64_t k = k0 + static_cast<int64_t>(i);
            V3 d = V3::Zero();
            if (k > k0) d += to_eigen((*frames)[static_cast<size_t>(s0 + k - 1)]) * V3::UnitX();
            if (k < k1) d += to_eigen((*frames)[static_cast<size_t>(s0 + k)]) * V3::UnitX();
            const V3 t = at(tan, i);
            const V3 p = d - d.dot(t) * t;
            if (p.norm() > 1e-6 * std::max(1.0, d.norm())) {
              const V3 u = p.normalized();
              for (size_t c = 0; c < 3; ++c) nrm[3 * i + c] = u[static_cast<Eigen::Index>(c)];
            }
          }
        }
      } else {
        for (size_t i = 0; i < n; ++i) {
          const V3 t = at(tan, i);
          const Vec3 s = plane_spoke({t.x(), t.y(), t.z()});
          for (size_t c = 0; c < 3; ++c) nrm[3 * i + c] = s[c];
        }
      }
      for (size_t i = 0; i < n; ++i) {
        const size_t g = static_cast<size_t>(g0 + k0) + i;
        const size_t atom = static_cast<size_t>(chain_.branch_atoms[g]);
        const double r = chain_.radius[atom];
        const V3 t = at(tan, i), u = at(nrm, i), w = t.cross(u), p = at(pts, i);
        if (first_spokes) {
          for (size_t c = 0; c < 3; ++c) (*first_spokes)[3 * g + c] = u[static_cast<Eigen::Index>(c)];
        }
        for (size_t j = 0; j < m; ++j) {
          const V3 v = p + r * (cos_t[j] * u + sin_t[j] * w);
          for (size_t c = 0; c < 3; ++c) out[3 * (g * m + j) + c] = static_cast<float>(v[static_cast<Eigen::Index>(c)]);
        }
      }
    });
  }
}

double max_spoke_turn_deg(const VesselChain& ch, const std::vector<double>& x, const std::vector<double>& spokes) {
  double worst = 0;
  std::vector<double> pts, tan;
  for (int32_t b = 0; b < ch.branch_count(); ++b) {
    const int64_t g0 = ch.branch_offsets[static_cast<size_t>(b)], n = ch.branch_offsets[static_cast<size_t>(b) + 1] - g0;
    pts.resize(3 * static_cast<size_t>(n));
    tan.resize(3 * static_cast<size_t>(n));
    for (int64_t i = 0; i < n; ++i) {
      const size_t atom = static_cast<size_t>(ch.branch_atoms[static_cast<size_t>(g0 + i)]);
      for (size_t c = 0; c < 3; ++c) pts[3 * static_cast<size_t>(i) + c] = x[3 * atom + c];
    }
    polyline_tangents(pts.data(), static_cast<size_t>(n), tan.data());
    for (int64_t i = 0; i + 1 < n; ++i) {
      const V3 t0 = at(tan, static_cast<size_t>(i)), t1 = at(tan, static_cast<size_t>(i + 1));
      const V3 u0 = at(spokes, static_cast<size_t>(g0 + i)), u1 = at(spokes, static_cast<size_t>(g0 + i + 1));
      const V3 moved = Q::FromTwoVectors(t0, t1) * u0;
      const double angle = std::atan2(moved.cross(u1).dot(t1), moved.dot(u1));
      worst = std::max(worst, std::abs(angle) * 180 / std::numbers::pi);
    }
  }
  return worst;
}

}  // namespace ctsurg::sim
