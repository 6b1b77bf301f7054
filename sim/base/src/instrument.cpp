#include "ctsurg/sim/base/instrument.h"

#include "ctsurg/core/error.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>
#include <vector>

namespace ctsurg::sim {
namespace {

std::string point_text(const double* p) {
  std::ostringstream s;
  s << "(" << p[0] << ", " << p[1] << ", " << p[2] << ") mm";
  return s.str();
}

double signed_volume(const TriangleMesh& m) {
  double v6 = 0;
  for (size_t t = 0; t < m.faces.size(); t += 3) {
    const double* a = &m.vertices[3 * m.faces[t]];
    const double* b = &m.vertices[3 * m.faces[t + 1]];
    const double* c = &m.vertices[3 * m.faces[t + 2]];
    v6 += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
  }
  return v6 / 6;
}

}  // namespace

TriangleMesh checked_instrument_mesh(TriangleMesh mesh, const std::string& file,
                                     const std::function<void(const std::string&)>& note) {
  const size_t nf = mesh.faces.size() / 3, nv = mesh.vertices.size() / 3;
  if (nf == 0) throw InputError(file, "faces", "the instrument has no face");
  if (static_cast<int64_t>(nf) > kMaxInstrumentFaces) {
    throw InputError(file, "faces", std::to_string(nf) + " faces; an instrument may have at most " + std::to_string(kMaxInstrumentFaces) +
                                        " (decimate it: contact reads a distance grid, not the faces)");
  }
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    if (!std::isfinite(mesh.vertices[i])) throw InputError(file, "vertices", "vertex " + std::to_string(i / 3) + " is not finite");
    lo[i % 3] = std::min(lo[i % 3], mesh.vertices[i]);
    hi[i % 3] = std::max(hi[i % 3], mesh.vertices[i]);
  }
  const double size = std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
  if (!(size >= kMinInstrumentSizeMm && size <= kMaxInstrumentSizeMm)) {
    throw InputError(file, "vertices", "the instrument is " + std::to_string(size) + " mm across; expected " +
                                           std::to_string(kMinInstrumentSizeMm) + " to " + std::to_string(kMaxInstrumentSizeMm) +
                                           " mm (the file's units must be millimetres)");
  }
  for (size_t t = 0; t < nf; ++t) {
    const uint32_t* f = &mesh.faces[3 * t];
    for (int k = 0; k < 3; ++k)
      if (f[k] >= nv) throw InputError(file, "faces", "face " + std::to_string(t) + " refers to a missing vertex");
    const double* a = &mesh.vertices[3 * f[0]];
    const double* b = &mesh.vertices[3 * f[1]];
    const double* c = &mesh.vertices[3 * f[2]];
    const double e[3][3] = {{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, {c[0] - b[0], c[1] - b[1], c[2] - b[2]}, {a[0] - c[0], a[1] - c[1], a[2] - c[2]}};
    const double n[3] = {e[0][1] * e[1][2] - e[0][2] * e[1][1], e[0][2] * e[1][0] - e[0][0] * e[1][2], e[0][0] * e[1][1] - e[0][1] * e[1][0]};
    const double twice_area = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    double longest = 0;
    for (const auto& ed : e) longest = std::max(longest, std::sqrt(ed[0] * ed[0] + ed[1] * ed[1] + ed[2] * ed[2]));
    if (!(longest > 0) || twice_area / longest < 1e-5 * size) {
      throw InputError(file, "faces", "face " + std::to_string(t) + " at " + point_text(a) +
                                          " is degenerate (its corners are on a line or coincide); remove it or repair the mesh");
    }
  }
  // Closed and consistently oriented: each directed edge once, and its reverse once.
  std::vector<std::pair<uint64_t, uint32_t>> edges;  // (from << 32 | to, face)
  edges.reserve(3 * nf);
  for (size_t t = 0; t < nf; ++t)
    for (int k = 0; k < 3; ++k) {
      const uint64_t from = mesh.faces[3 * t + static_cast<size_t>(k)], to = mesh.faces[3 * t + static_cast<size_t>((k + 1) % 3)];
      edges.emplace_back(from << 32 | to, static_cast<uint32_t>(t));
    }
  std::sort(edges.begin(), edges.end());
  for (size_t e = 0; e < edges.size(); ++e) {
    const uint64_t key = edges[e].first;
    const uint32_t from = static_cast<uint32_t>(key >> 32), to = static_cast<uint32_t>(key & 0xffffffffu);
    if (e + 1 < edges.size() && edges[e + 1].first == key) {
      throw InputError(file, "faces", "faces " + std::to_string(edges[e].second) + " and " + std::to_string(edges[e + 1].second) +
                                          " run along the edge " + point_text(&mesh.vertices[3 * static_cast<size_t>(from)]) +
                                          " the same way: the mesh is not consistently oriented or an edge has more than two faces");
    }
    const uint64_t reverse = static_cast<uint64_t>(to) << 32 | from;
    if (!std::binary_search(edges.begin(), edges.end(), std::make_pair(reverse, 0u),
                            [](const auto& x, const auto& y) { return x.first < y.first; })) {
      throw InputError(file, "faces", "the mesh is not closed: the edge from " + point_text(&mesh.vertices[3 * static_cast<size_t>(from)]) +
                                          " to " + point_text(&mesh.vertices[3 * static_cast<size_t>(to)]) + " of face " +
                                          std::to_string(edges[e].second) + " has no neighbouring face (a hole)");
    }
  }
  if (signed_volume(mesh) < 0) {
    for (size_t t = 0; t < nf; ++t) std::swap(mesh.faces[3 * t + 1], mesh.faces[3 * t + 2]);
    if (note) note(file + ": the faces pointed inwards; flipped");
  }
  return mesh;
}

Instrument make_instrument(TriangleMesh mesh, const std::string& name, double spacing_mm,
                           const std::function<void(const std::string&)>& note) {
  Instrument ins;
  ins.name = name;
  ins.mesh = checked_instrument_mesh(std::move(mesh), name, note);
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (size_t i = 0; i < ins.mesh.vertices.size(); ++i) {
    lo[i % 3] = std::min(lo[i % 3], ins.mesh.vertices[i]);
    hi[i % 3] = std::max(hi[i % 3], ins.mesh.vertices[i]);
  }
  const double ext[3] = {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
  ins.size_mm = std::sqrt(ext[0] * ext[0] + ext[1] * ext[1] + ext[2] * ext[2]);
  ins.volume_mm3 = signed_volume(ins.mesh);
  if (spacing_mm != 0 && !(std::isfinite(spacing_mm) && spacing_mm > 0)) {
    throw InputError(name, "spacing_mm", "must be > 0 (or 0: automatic)");
  }
  // Automatic spacing: a fifth of the instrument's thickness, estimated as 2 V / A (a plate's
  // thickness, a rod's radius; a bent blade's bounding box would say nothing of it).
  double area = 0;
  for (size_t t = 0; t < ins.mesh.faces.size(); t += 3) {
    const double* a = &ins.mesh.vertices[3 * ins.mesh.faces[t]];
    const double* b = &ins.mesh.vertices[3 * ins.mesh.faces[t + 1]];
    const double* c = &ins.mesh.vertices[3 * ins.mesh.faces[t + 2]];
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    area += 0.5 * std::sqrt(std::pow(u[1] * w[2] - u[2] * w[1], 2) + std::pow(u[2] * w[0] - u[0] * w[2], 2) +
                            std::pow(u[0] * w[1] - u[1] * w[0], 2));
  }
  ins.thickness_mm = 2 * ins.volume_mm3 / area;
  double h = spacing_mm > 0 ? spacing_mm : std::clamp(ins.thickness_mm / 5, 0.05, 0.5);
  const auto nodes = [&](double s) {
    double n = 1;
    for (const double e : ext) n *= std::ceil(e / s) + 7;
    return n;
  };
  if (spacing_mm > 0 && nodes(h) > static_cast<double>(kMaxInstrumentGridNodes)) {
    throw InputError(name, "spacing_mm", "a " + std::to_string(h) + " mm grid over the instrument has " + std::to_string(nodes(h)) +
                                             " nodes; at most " + std::to_string(kMaxInstrumentGridNodes) + ": give a coarser spacing");
  }
  while (nodes(h) > static_cast<double>(kMaxInstrumentGridNodes)) h *= 1.25;
  ins.distance = bake_signed_distance_grid(ins.mesh, h, 3);
  if (note) {
    note(name + ": instrument of " + std::to_string(ins.mesh.faces.size() / 3) + " faces, " + std::to_string(ins.size_mm) +
         " mm across; distance grid " + std::to_string(ins.distance.dims[0]) + " x " + std::to_string(ins.distance.dims[1]) + " x " +
         std::to_string(ins.distance.dims[2]) + " at " + std::to_string(h) + " mm");
  }
  return ins;
}

std::shared_ptr<const Instrument> load_instrument(const std::filesystem::path& path, double spacing_mm,
                                                  const std::function<void(const std::string&)>& note) {
  return std::make_shared<const Instrument>(make_instrument(read_triangle_mesh(path), path.string(), spacing_mm, note));
}

InstrumentView instrument_view(const Instrument& instrument, const Quaternion& q, const std::array<double, 3>& centre) {
  InstrumentView v;
  const SignedDistanceGrid& g = instrument.distance;
  v.phi = g.phi.data();
  v.nx = g.dims[0], v.ny = g.dims[1], v.nz = g.dims[2];
  v.ox = g.origin[0], v.oy = g.origin[1], v.oz = g.origin[2];
  v.spacing = g.spacing;
  const std::array<double, 9> r = rotation_matrix(q);
  for (size_t i = 0; i < 9; ++i) v.r[i] = r[i];
  v.cx = centre[0], v.cy = centre[1], v.cz = centre[2];
  return v;
}

void check_instrument_view(const InstrumentView& view, const std::string& where, const std::string& field) {
  if (view.phi == nullptr || view.nx < 2 || view.ny < 2 || view.nz < 2 || !(view.spacing > 0)) {
    throw InputError(where, field, "the instrument's distance grid is empty");
  }
}

}  // namespace ctsurg::sim
