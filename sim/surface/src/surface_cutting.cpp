#include "ctsurg/sim/surface/surface_cutting.h"

#include "ctsurg/core/error.h"
#include "ctsurg/sim/surface/kernels/surface_cutting_impl.h"

#include <algorithm>

namespace ctsurg::sim {

namespace {

TriangleView view_of(const Triangle& blade) {
  TriangleView t{};
  for (int c = 0; c < 3; ++c) {
    t.a[c] = blade.a[static_cast<size_t>(c)];
    t.b[c] = blade.b[static_cast<size_t>(c)];
    t.c[c] = blade.c[static_cast<size_t>(c)];
  }
  return t;
}

}  // namespace

int64_t remove_crossed_triangles(std::vector<uint32_t>& triangles, const std::vector<float>& vertices, const Triangle& blade) {
  if (triangles.size() % 3 != 0) throw InputError("surface cut", "triangles", "expected #F x 3");
  for (const uint32_t v : triangles)
    if (3 * static_cast<size_t>(v) + 2 >= vertices.size()) throw InputError("surface cut", "triangles", "vertex id out of range");
  const TriangleView t = view_of(blade);
  // Only triangles near the blade can be crossed: a box test first keeps a cut step proportional to
  // the blade's size, not the surface's.
  double lo[3], hi[3];
  for (int c = 0; c < 3; ++c) {
    lo[c] = std::min({t.a[c], t.b[c], t.c[c]});
    hi[c] = std::max({t.a[c], t.b[c], t.c[c]});
  }
  int64_t removed = 0;
  const int64_t nf = static_cast<int64_t>(triangles.size() / 3);
  std::vector<uint32_t> kept;
  kept.reserve(triangles.size());
  for (int64_t f = 0; f < nf; ++f) {
    bool near = true;
    for (int c = 0; c < 3 && near; ++c) {
      double a = 1e300, b = -1e300;
      for (int e = 0; e < 3; ++e) {
        const double p = vertices[3 * triangles[static_cast<size_t>(3 * f + e)] + static_cast<size_t>(c)];
        a = std::min(a, p);
        b = std::max(b, p);
      }
      near = b >= lo[c] && a <= hi[c];
    }
    if (near && triangle_crosses_blade(triangles.data(), vertices.data(), t, f)) {
      ++removed;
      continue;
    }
    kept.insert(kept.end(), triangles.begin() + 3 * f, triangles.begin() + 3 * f + 3);
  }
  triangles.swap(kept);
  return removed;
}

SurfaceCutResult cut_surface(std::vector<uint32_t>& triangles, SurfaceCoupling& coupling, const std::vector<float>& vertices,
                             const ParticleState& state, const Triangle& blade) {
  const int64_t nv = coupling.vertex_count();
  if (static_cast<int64_t>(vertices.size()) != 3 * nv) throw InputError("surface cut", "vertices", "expected #V x 3");
  SurfaceCutResult r;
  r.triangles_removed = remove_crossed_triangles(triangles, vertices, blade);
  const TriangleView t = view_of(blade);
  double lo[3], hi[3];
  for (int c = 0; c < 3; ++c) {
    lo[c] = std::min({t.a[c], t.b[c], t.c[c]});
    hi[c] = std::max({t.a[c], t.b[c], t.c[c]});
  }
  // A vertex's slots reach at most one cell diagonal away; the box test on the vertex uses the blade
  // box grown by the longest vertex-particle distance, computed on the fly (cheap: one pass).
  for (int64_t i = 0; i < nv; ++i) {
    double reach = 0;
    for (int c = 0; c < 8; ++c) {
      const int32_t j = coupling.particles[static_cast<size_t>(8 * i + c)];
      if (j < 0) continue;
      const double d[3] = {state.x[static_cast<size_t>(j)] - vertices[static_cast<size_t>(3 * i)],
                           state.y[static_cast<size_t>(j)] - vertices[static_cast<size_t>(3 * i + 1)],
                           state.z[static_cast<size_t>(j)] - vertices[static_cast<size_t>(3 * i + 2)]};
      reach = std::max({reach, std::abs(d[0]), std::abs(d[1]), std::abs(d[2])});
    }
    bool near = true;
    for (int c = 0; c < 3 && near; ++c) {
      const double p = vertices[static_cast<size_t>(3 * i + c)];
      near = p + reach >= lo[c] && p - reach <= hi[c];
    }
    if (!near) continue;
    r.slots_detached += detach_vertex(coupling.particles.data(), coupling.weights.data(), vertices.data(), state.x.data(),
                                      state.y.data(), state.z.data(), t, i);
  }
  return r;
}

}  // namespace ctsurg::sim
