#include "ctsurg/core/centerline_file.h"

#include "ctsurg/core/checked_write.h"
#include "ctsurg/core/ctsurg_file.h"
#include "ctsurg/core/error.h"
#include "ctsurg/core/finite_values.h"
#include "ctsurg/core/hdf5_file.h"

#include <array>
#include <charconv>
#include <cmath>
#include <string>

namespace ctsurg {

namespace {

constexpr double kNodeToleranceMm = 1e-6;

// Shortest text that reads back as the same double (std::to_chars), so the sidecar is exact and
// deterministic.
void append_number(std::string& out, double v) {
  std::array<char, 32> buf{};
  const auto r = std::to_chars(buf.data(), buf.data() + buf.size(), v);
  out.append(buf.data(), r.ptr);
}

// Legacy VTK ASCII polydata: one polyline (LINES cell) per branch, the radius as point data. ParaView
// opens it directly (a tube filter scaled by "radius" shows the vessel).
std::string centerline_vtk(const Centerline& c, const std::string& h5_name) {
  const int64_t np = c.point_count(), nb = c.branch_count();
  std::string s;
  s.reserve(static_cast<std::size_t>(np) * 64 + 256);
  s += "# vtk DataFile Version 3.0\nctsurg centerline sidecar of " + h5_name + ", LPS mm\nASCII\nDATASET POLYDATA\n";
  s += "POINTS " + std::to_string(np) + " double\n";
  for (int64_t p = 0; p < np; ++p) {
    for (int a = 0; a < 3; ++a) {
      if (a) s += ' ';
      append_number(s, c.points[static_cast<std::size_t>(3 * p + a)]);
    }
    s += '\n';
  }
  s += "LINES " + std::to_string(nb) + " " + std::to_string(nb + np) + "\n";
  for (int64_t b = 0; b < nb; ++b) {
    const int64_t first = c.branch_offsets[static_cast<std::size_t>(b)], last = c.branch_offsets[static_cast<std::size_t>(b + 1)];
    s += std::to_string(last - first);
    for (int64_t p = first; p < last; ++p) s += " " + std::to_string(p);
    s += '\n';
  }
  s += "POINT_DATA " + std::to_string(np) + "\nSCALARS radius double 1\nLOOKUP_TABLE default\n";
  for (int64_t p = 0; p < np; ++p) {
    append_number(s, c.radius[static_cast<std::size_t>(p)]);
    s += '\n';
  }
  return s;
}

}  // namespace

void validate_centerline(const Centerline& c, const std::string& file) {
  if (c.points.size() % 3 != 0) throw InputError(file, "/centerline/points", "length is not a multiple of 3");
  if (c.nodes.size() % 3 != 0) throw InputError(file, "/centerline/nodes", "length is not a multiple of 3");
  if (c.branch_nodes.size() % 2 != 0) throw InputError(file, "/centerline/branch_nodes", "length is not a multiple of 2");
  if (c.branch_count() < 1) throw InputError(file, "/centerline/branch_offsets", "the centerline has no branch");
  const int64_t np = c.point_count(), nb = c.branch_count(), nn = c.node_count();
  if (static_cast<int64_t>(c.points.size()) != 3 * np) {
    throw InputError(file, "/centerline/radius",
                     "expected one radius per point (" + std::to_string(c.points.size() / 3) + " points), got " +
                         std::to_string(np));
  }
  if (static_cast<int64_t>(c.branch_nodes.size()) != 2 * nb) {
    throw InputError(file, "/centerline/branch_nodes",
                     "expected two nodes per branch (" + std::to_string(nb) + " branches), got " +
                         std::to_string(c.branch_nodes.size() / 2) + " rows");
  }
  if (c.branch_offsets.front() != 0 || c.branch_offsets.back() != np) {
    throw InputError(file, "/centerline/branch_offsets",
                     "must start at 0 and end at the point count " + std::to_string(np));
  }
  for (int64_t b = 0; b < nb; ++b) {
    const int64_t n = c.branch_offsets[static_cast<std::size_t>(b + 1)] - c.branch_offsets[static_cast<std::size_t>(b)];
    if (n < 2) {
      throw InputError(file, "/centerline/branch_offsets",
                       "branch " + std::to_string(b) + " has " + std::to_string(n) + " points (at least 2)");
    }
  }
  require_finite(c.points, 3, file, "/centerline/points");
  require_finite(c.nodes, 3, file, "/centerline/nodes");
  for (std::size_t p = 0; p < c.radius.size(); ++p) {
    if (!(std::isfinite(c.radius[p]) && c.radius[p] > 0.0)) {
      throw InputError(file, "/centerline/radius",
                       "radius at point " + std::to_string(p) + " is " + std::to_string(c.radius[p]) +
                           " (must be finite and positive)");
    }
  }
  std::vector<int> used(static_cast<std::size_t>(nn), 0);
  for (int64_t b = 0; b < nb; ++b) {
    for (int e = 0; e < 2; ++e) {
      const int32_t node = c.branch_nodes[static_cast<std::size_t>(2 * b + e)];
      if (node < 0 || node >= nn) {
        throw InputError(file, "/centerline/branch_nodes",
                         "branch " + std::to_string(b) + ": node index " + std::to_string(node) + " out of range [0, " +
                             std::to_string(nn) + ")");
      }
      used[static_cast<std::size_t>(node)] = 1;
      const int64_t p = e == 0 ? c.branch_offsets[static_cast<std::size_t>(b)] : c.branch_offsets[static_cast<std::size_t>(b + 1)] - 1;
      for (int a = 0; a < 3; ++a) {
        const double d = c.points[static_cast<std::size_t>(3 * p + a)] - c.nodes[static_cast<std::size_t>(3 * node + a)];
        if (!(std::abs(d) <= kNodeToleranceMm)) {
          throw InputError(file, "/centerline/branch_nodes",
                           "branch " + std::to_string(b) + "'s " + (e == 0 ? "first" : "last") + " point is not at node " +
                               std::to_string(node) + " (" + std::to_string(std::abs(d)) + " mm apart)");
        }
      }
    }
  }
  for (int64_t n = 0; n < nn; ++n) {
    if (!used[static_cast<std::size_t>(n)]) {
      throw InputError(file, "/centerline/nodes", "node " + std::to_string(n) + " ends no branch");
    }
  }
  for (const double s : c.source_spacing_mm) {
    if (!(std::isfinite(s) && s >= 0.0)) {
      throw InputError(file, "/centerline/source_spacing_mm", "must be finite and >= 0 mm (0: unknown)");
    }
  }
}

std::filesystem::path centerline_vtk_path_for(const std::filesystem::path& h5_path) {
  std::filesystem::path p = h5_path;
  return p.replace_extension(".vtk");
}

void write_centerline_file(const std::filesystem::path& path, const Centerline& c, const Provenance& provenance,
                           OutputUnit* unit) {
  validate_centerline(c, path.string());
  OutputUnit own;
  OutputUnit& outputs = unit ? *unit : own;
  AtomicOutput& out = outputs.add(path);
  AtomicOutput& sidecar = outputs.add(centerline_vtk_path_for(path));
  const uint64_t np = static_cast<uint64_t>(c.point_count()), nb = static_cast<uint64_t>(c.branch_count()),
                 nn = static_cast<uint64_t>(c.node_count());
  {
    // The ctsurg file frame of ctsurg_file.h, with a VTK sidecar instead of XDMF (XDMF has no polyline
    // topology that ParaView reads with per-branch lengths).
    h5::File f = h5::File::create(out.temp_path(), path.string());
    {
      h5::Group root = f.root();
      root.set_attribute("ctsurg_format", std::string("centerline"));
      root.set_attribute("ctsurg_format_version", int64_t{1});
      provenance.write(root);
      h5::Group s = root.create_group("centerline");
      s.set_attribute("frame", std::string("LPS"));
      s.set_attribute("units", std::string("mm"));
      s.set_attribute("points", static_cast<int64_t>(np));
      s.set_attribute("branches", static_cast<int64_t>(nb));
      s.set_attribute("nodes", static_cast<int64_t>(nn));
      s.set_attribute("label", static_cast<int64_t>(c.label));
      s.set_attribute("source_spacing_mm", std::span<const double>(c.source_spacing_mm));
      s.set_attribute("parameters", c.parameters);
      const std::array<uint64_t, 2> p3{np, 3}, b2{nb, 2}, n3{nn, 3};
      const std::array<uint64_t, 1> p1{np}, o1{nb + 1};
      s.write_dataset("points", c.points, p3);
      s.write_dataset("radius", c.radius, p1);
      s.write_dataset("branch_offsets", c.branch_offsets, o1);
      s.write_dataset("branch_nodes", c.branch_nodes, b2);
      s.write_dataset("nodes", c.nodes, n3);
    }
    f.close();
  }
  write_file_checked(sidecar.temp_path(), centerline_vtk(c, path.filename().string()), sidecar.path().string());
  if (!unit) own.commit();
}

Centerline read_centerline_file(const std::filesystem::path& path) {
  const h5::File f = open_ctsurg_file(path, "centerline");
  const h5::Group s = f.root().open_group("centerline");
  const std::string file = path.string();
  Centerline c;
  std::vector<uint64_t> shape;
  // cols == 0: a 1-D dataset; rows == 0: any number of rows.
  const auto read = [&](const char* name, auto& out, uint64_t cols, uint64_t rows) {
    using T = typename std::decay_t<decltype(out)>::value_type;
    out = s.template read_dataset<T>(name, &shape);
    const bool ok = cols == 0 ? shape.size() == 1 : (shape.size() == 2 && shape[1] == cols);
    if (!ok || (rows != 0 && shape[0] != rows)) {
      const std::string r = rows ? std::to_string(rows) : std::string("n");
      throw InputError(file, s.path() + "/" + name,
                       "expected shape (" + r + (cols ? ", " + std::to_string(cols) : std::string()) + ")");
    }
  };
  const auto count = [&](const char* name) {
    const int64_t n = s.int_attribute(name);
    if (n < 0) throw InputError(file, s.path() + "/@" + name, "must be >= 0, got " + std::to_string(n));
    return static_cast<uint64_t>(n);
  };
  const uint64_t np = count("points"), nb = count("branches"), nn = count("nodes");
  if (nb < 1) throw InputError(file, "/centerline/@branches", "the centerline has no branch");
  read("points", c.points, 3, np);
  read("radius", c.radius, 0, np);
  read("branch_offsets", c.branch_offsets, 0, nb + 1);
  read("branch_nodes", c.branch_nodes, 2, nb);
  read("nodes", c.nodes, 3, nn);
  if (s.string_attribute("frame") != "LPS" || s.string_attribute("units") != "mm") {
    throw InputError(file, "/centerline/@frame", "expected frame LPS and units mm");
  }
  const int64_t label = s.int_attribute("label");
  if (label < 0 || label > 65535) {
    throw InputError(file, "/centerline/@label", "must be in [0, 65535], got " + std::to_string(label));
  }
  c.label = static_cast<uint16_t>(label);
  const std::vector<double> spacing = s.doubles_attribute("source_spacing_mm");
  if (spacing.size() != 3) throw InputError(file, "/centerline/@source_spacing_mm", "expected 3 values");
  for (int a = 0; a < 3; ++a) c.source_spacing_mm[static_cast<std::size_t>(a)] = spacing[static_cast<std::size_t>(a)];
  c.parameters = s.string_attribute("parameters");
  validate_centerline(c, file);
  return c;
}

}  // namespace ctsurg
