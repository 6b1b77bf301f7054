#include "ctsurg/core/trajectory_file.h"

#include "ctsurg/core/ctsurg_file.h"
#include "ctsurg/core/error.h"
#include "ctsurg/core/finite_values.h"
#include "ctsurg/core/hdf5_file.h"

#include <array>
#include <cmath>
#include <sstream>

namespace ctsurg {

namespace {

std::string join(const std::vector<std::string>& parts, char sep) {
  std::string out;
  for (size_t i = 0; i < parts.size(); ++i) out += (i ? std::string(1, sep) : std::string()) + parts[i];
  return out;
}

std::vector<std::string> split(const std::string& text, char sep) {
  std::vector<std::string> out;
  if (text.empty()) return out;
  std::string part;
  std::istringstream in(text);
  while (std::getline(in, part, sep)) out.push_back(part);
  if (text.back() == sep) out.emplace_back();
  return out;
}

// XDMF 3: a temporal collection with one triangle-mesh grid per frame; each frame's geometry is a
// hyperslab of /trajectory/surface/vertices, its displacement (vertices - rest) a Function item.
std::string trajectory_xdmf(const std::string& h5, const Trajectory& t) {
  const int64_t nf = t.frame_count(), nv = t.vertex_count(), np = t.particle_count();
  const std::string v = std::to_string(nv), f = std::to_string(nf);
  std::ostringstream x;
  x.precision(17);
  x << "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
    << "<!-- ctsurg sidecar: opens " << h5 << " in ParaView (a time series). LPS millimetres, seconds. -->\n"
    << "<Xdmf Version=\"3.0\">\n  <Domain>\n"
    << "    <Grid Name=\"surface\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  const auto slab = [&](const std::string& dataset, int64_t frame, const std::string& rows, const std::string& frames) {
    std::ostringstream s;
    s << "<DataItem ItemType=\"HyperSlab\" Dimensions=\"" << rows << " 3\" Type=\"HyperSlab\">"
      << "<DataItem Dimensions=\"3 3\" Format=\"XML\">" << frame << " 0 0 1 1 1 1 " << rows << " 3</DataItem>"
      << "<DataItem Dimensions=\"" << frames << " " << rows << " 3\" NumberType=\"Float\" Precision=\"4\" Format=\"HDF\">"
      << h5 << ":" << dataset << "</DataItem></DataItem>";
    return s.str();
  };
  for (int64_t i = 0; i < nf; ++i) {
    const int32_t k = t.topology_of_frame[i];
    const std::string nt = std::to_string(t.topologies[k].size() / 3);
    x << "      <Grid Name=\"frame " << i << "\" GridType=\"Uniform\">\n"
      << "        <Time Value=\"" << t.time[i] << "\"/>\n"
      << "        <Topology TopologyType=\"Triangle\" NumberOfElements=\"" << nt << "\">\n"
      << "          <DataItem Dimensions=\"" << nt << " 3\" NumberType=\"UInt\" Precision=\"4\" Format=\"HDF\">" << h5
      << ":/trajectory/surface/topologies/" << k << "</DataItem>\n"
      << "        </Topology>\n"
      << "        <Geometry GeometryType=\"XYZ\">" << slab("/trajectory/surface/vertices", i, v, f) << "</Geometry>\n"
      << "        <Attribute Name=\"displacement_mm\" AttributeType=\"Vector\" Center=\"Node\">\n"
      << "          <DataItem ItemType=\"Function\" Function=\"$0 - $1\" Dimensions=\"" << v << " 3\">"
      << slab("/trajectory/surface/vertices", i, v, f) << "<DataItem Dimensions=\"" << v
      << " 3\" NumberType=\"Float\" Precision=\"4\" Format=\"HDF\">" << h5
      << ":/trajectory/surface/rest_vertices</DataItem></DataItem>\n"
      << "        </Attribute>\n";
    if (!t.vertex_region.empty()) {
      // Row i of (F, V): a hyperslab of start (i, 0), stride (1, 1), count (1, V).
      x << "        <Attribute Name=\"local_region\" AttributeType=\"Scalar\" Center=\"Node\">\n"
        << "          <DataItem ItemType=\"HyperSlab\" Dimensions=\"" << v << "\" Type=\"HyperSlab\">"
        << "<DataItem Dimensions=\"3 2\" Format=\"XML\">" << i << " 0 1 1 1 " << v << "</DataItem>"
        << "<DataItem Dimensions=\"" << f << " " << v << "\" NumberType=\"UChar\" Precision=\"1\" Format=\"HDF\">" << h5
        << ":/trajectory/surface/vertex_region</DataItem></DataItem>\n"
        << "        </Attribute>\n";
    }
    x << "      </Grid>\n";
  }
  x << "    </Grid>\n";
  if (np > 0) {
    const std::string p = std::to_string(np);
    x << "    <Grid Name=\"particles\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
    for (int64_t i = 0; i < nf; ++i) {
      x << "      <Grid Name=\"particles " << i << "\" GridType=\"Uniform\">\n"
        << "        <Time Value=\"" << t.time[i] << "\"/>\n";
      if (t.element_count() > 0) {
        // The FE mesh itself (quadratic tets: Tetrahedron_10, VTK_QUADRATIC_TETRA's order) with its displacement.
        const std::string e = std::to_string(t.element_count()), npe = std::to_string(t.element_nodes);
        x << "        <Topology TopologyType=\"" << (t.element_nodes == 10 ? "Tetrahedron_10" : "Tetrahedron") << "\" NumberOfElements=\"" << e
          << "\">\n"
          << "          <DataItem Dimensions=\"" << e << " " << npe << "\" NumberType=\"Int\" Precision=\"4\" Format=\"HDF\">" << h5
          << ":/trajectory/particles/elements</DataItem>\n"
          << "        </Topology>\n";
      } else {
        x << "        <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << p << "\"/>\n";
      }
      x << "        <Geometry GeometryType=\"XYZ\">" << slab("/trajectory/particles/positions", i, p, f) << "</Geometry>\n";
      if (t.element_count() > 0) {
        x << "        <Attribute Name=\"displacement_mm\" AttributeType=\"Vector\" Center=\"Node\">\n"
          << "          <DataItem ItemType=\"Function\" Function=\"$0 - $1\" Dimensions=\"" << p << " 3\">"
          << slab("/trajectory/particles/positions", i, p, f) << "<DataItem Dimensions=\"" << p
          << " 3\" NumberType=\"Float\" Precision=\"4\" Format=\"HDF\">" << h5 << ":/trajectory/particles/rest_positions</DataItem></DataItem>\n"
          << "        </Attribute>\n";
      }
      x << "      </Grid>\n";
    }
    x << "    </Grid>\n";
  }
  x << "  </Domain>\n</Xdmf>\n";
  return x.str();
}

}  // namespace

const TrajectoryMetric* Trajectory::metric(const std::string& name) const {
  for (const auto& m : metrics) {
    if (m.name == name) return &m;
  }
  return nullptr;
}

void validate_trajectory(const Trajectory& t, const std::string& file) {
  const size_t nf = t.time.size();
  if (nf == 0) throw InputError(file, "/trajectory/time", "the trajectory has no frames");
  if (t.rest_vertices.empty() || t.rest_vertices.size() % 3 != 0) {
    throw InputError(file, "/trajectory/surface/rest_vertices", "expected (V, 3) with V > 0");
  }
  const size_t nv = t.rest_vertices.size() / 3;
  if (t.vertices.size() != nf * nv * 3) {
    throw InputError(file, "/trajectory/surface/vertices",
                     "expected (" + std::to_string(nf) + ", " + std::to_string(nv) + ", 3) for " + std::to_string(nf) +
                         " frames of " + std::to_string(nv) + " vertices");
  }
  if (t.topologies.empty()) throw InputError(file, "/trajectory/surface/topologies", "no topology");
  for (size_t k = 0; k < t.topologies.size(); ++k) {
    const std::string where = "/trajectory/surface/topologies/" + std::to_string(k);
    if (t.topologies[k].size() % 3 != 0) throw InputError(file, where, "expected (T, 3)");
    for (const uint32_t i : t.topologies[k]) {
      if (i >= nv) {
        throw InputError(file, where, "vertex index " + std::to_string(i) + " out of range [0, " + std::to_string(nv) + ")");
      }
    }
  }
  if (!t.closing_triangles.empty()) {
    if (t.closing_triangles.size() != t.topologies.size()) {
      throw InputError(file, "/trajectory/surface/closing_triangles", "expected one entry per topology (" + std::to_string(t.topologies.size()) + ")");
    }
    for (size_t k = 0; k < t.topologies.size(); ++k) {
      if (t.closing_triangles[k] < 0 || static_cast<uint64_t>(t.closing_triangles[k]) > t.topologies[k].size() / 3) {
        throw InputError(file, "/trajectory/surface/closing_triangles", "entry " + std::to_string(k) + " is not in [0, the topology's triangles]");
      }
    }
  }
  if (!t.vertex_region.empty()) {
    if (t.vertex_region.size() != nf * nv) {
      throw InputError(file, "/trajectory/surface/vertex_region",
                       "expected (" + std::to_string(nf) + ", " + std::to_string(nv) + ") flags, one per frame and vertex");
    }
    for (size_t i = 0; i < t.vertex_region.size(); ++i) {
      if (t.vertex_region[i] > 2) {
        throw InputError(file, "/trajectory/surface/vertex_region",
                         "frame " + std::to_string(i / nv) + ", vertex " + std::to_string(i % nv) + ": flag " +
                             std::to_string(t.vertex_region[i]) + " is not 0 (outside), 1 (region) or 2 (interface)");
      }
    }
  }
  if (t.topology_of_frame.size() != nf) {
    throw InputError(file, "/trajectory/surface/topology_of_frame", "expected one entry per frame (" + std::to_string(nf) + ")");
  }
  for (const int32_t k : t.topology_of_frame) {
    if (k < 0 || static_cast<size_t>(k) >= t.topologies.size()) {
      throw InputError(file, "/trajectory/surface/topology_of_frame", "topology " + std::to_string(k) + " does not exist");
    }
  }
  for (size_t i = 1; i < nf; ++i) {
    if (!(t.time[i] > t.time[i - 1])) throw InputError(file, "/trajectory/time", "times must increase");
  }
  for (const auto& m : t.metrics) {
    if (m.name.empty() || m.name.find_first_of("/;") != std::string::npos) {
      throw InputError(file, "/trajectory/metrics", "metric name '" + m.name + "' is empty or contains '/' or ';'");
    }
    if (m.values.size() != nf) {
      throw InputError(file, "/trajectory/metrics/" + m.name, "expected one value per frame (" + std::to_string(nf) + ")");
    }
  }
  if (t.spheres.size() != nf * t.sphere_kinds.size() * 4) {
    throw InputError(file, "/trajectory/tools/spheres", "expected (F, S, 4) with S = the number of sphere kinds");
  }
  if (!t.sphere_loads.empty()) {
    if (t.sphere_loads.size() != nf * t.sphere_kinds.size() * 7) {
      throw InputError(file, "/trajectory/tools/sphere_loads", "expected (F, S, 7) with S = the number of sphere kinds");
    }
    require_finite(t.sphere_loads, 7, file, "/trajectory/tools/sphere_loads");
    for (size_t r = 0; r < t.sphere_loads.size(); r += 7) {
      if (t.sphere_loads[r] != 0.0 && t.sphere_loads[r] != 1.0) {
        throw InputError(file, "/trajectory/tools/sphere_loads", "row " + std::to_string(r / 7) + ": measured must be 0 or 1");
      }
    }
  }
  if (t.blades.size() % (nf * 7) != 0) throw InputError(file, "/trajectory/tools/blades", "expected (F, B, 7)");
  if (t.stitches.size() % (nf * 7) != 0) throw InputError(file, "/trajectory/tools/stitches", "expected (F, K, 7)");
  require_finite(t.stitches, 7, file, "/trajectory/tools/stitches");
  for (size_t r = 0; r < t.stitches.size(); r += 7) {
    if (t.stitches[r + 6] != 0.0 && t.stitches[r + 6] != 1.0) {
      throw InputError(file, "/trajectory/tools/stitches", "row " + std::to_string(r / 7) + ": placed must be 0 or 1");
    }
  }
  for (size_t k = 0; k < t.instruments.size(); ++k) {
    const TrajectoryInstrument& ins = t.instruments[k];
    const std::string where = "/trajectory/tools/instruments/" + std::to_string(k);
    if (ins.vertices.empty() || ins.vertices.size() % 3 != 0) throw InputError(file, where + "/vertices", "expected (V, 3) with V > 0");
    if (ins.triangles.empty() || ins.triangles.size() % 3 != 0) throw InputError(file, where + "/triangles", "expected (T, 3) with T > 0");
    for (const uint32_t v : ins.triangles) {
      if (v >= ins.vertices.size() / 3) throw InputError(file, where + "/triangles", "vertex id " + std::to_string(v) + " out of range");
    }
    require_finite(ins.vertices, 3, file, where + "/vertices");
  }
  if (t.instrument_poses.size() != nf * t.instruments.size() * 8) {
    throw InputError(file, "/trajectory/tools/instrument_poses", "expected (F, I, 8) with I = the number of instruments");
  }
  require_finite(t.instrument_poses, 8, file, "/trajectory/tools/instrument_poses");
  for (size_t r = 0; r < t.instrument_poses.size(); r += 8) {
    const double* p = &t.instrument_poses[r];
    if (std::abs(p[1] * p[1] + p[2] * p[2] + p[3] * p[3] + p[4] * p[4] - 1) > 1e-6) {
      throw InputError(file, "/trajectory/tools/instrument_poses", "row " + std::to_string(r / 8) + ": the rotation is not a unit quaternion");
    }
  }
  if (t.rest_particles.size() % 3 != 0 || t.particles.size() != nf * t.rest_particles.size()) {
    throw InputError(file, "/trajectory/particles", "expected rest_positions (P, 3) and positions (F, P, 3)");
  }
  // docs/sim.md: a trajectory never holds a non-finite value.
  require_finite(t.time, 1, file, "/trajectory/time");
  require_finite(t.rest_vertices, 3, file, "/trajectory/surface/rest_vertices");
  require_finite(t.vertices, 3 * nv, file, "/trajectory/surface/vertices (row = frame)");
  for (const auto& m : t.metrics) require_finite(m.values, 1, file, "/trajectory/metrics/" + m.name);
  require_finite(t.spheres, 4 * t.sphere_kinds.size(), file, "/trajectory/tools/spheres (row = frame)");
  require_finite(t.blades, 7, file, "/trajectory/tools/blades");
  if (!t.elements.empty() || t.element_nodes != 0) {
    if (t.rest_particles.empty()) throw InputError(file, "/trajectory/particles/elements", "elements need the particles");
    if (t.element_nodes != 4 && t.element_nodes != 10) throw InputError(file, "/trajectory/particles/elements", "expected 4 or 10 nodes per element");
    if (t.elements.empty() || t.elements.size() % static_cast<size_t>(t.element_nodes) != 0) {
      throw InputError(file, "/trajectory/particles/elements", "expected (E, " + std::to_string(t.element_nodes) + ") with E > 0");
    }
    const int64_t np = t.particle_count();
    for (size_t k = 0; k < t.elements.size(); ++k) {
      if (t.elements[k] < 0 || t.elements[k] >= np) {
        throw InputError(file, "/trajectory/particles/elements",
                         "element " + std::to_string(k / static_cast<size_t>(t.element_nodes)) + " names particle " + std::to_string(t.elements[k]) +
                             ", out of range [0, " + std::to_string(np) + ")");
      }
    }
  }
  require_finite(t.rest_particles, 3, file, "/trajectory/particles/rest_positions");
  require_finite(t.particles, t.rest_particles.size(), file, "/trajectory/particles/positions (row = frame)");
}

void write_trajectory_file(const std::filesystem::path& path, const Trajectory& t, const Provenance& provenance) {
  validate_trajectory(t, path.string());
  const uint64_t nf = t.time.size(), nv = static_cast<uint64_t>(t.vertex_count()),
                 ns = t.sphere_kinds.size(), nb = static_cast<uint64_t>(t.blade_count()),
                 np = static_cast<uint64_t>(t.particle_count());
  write_ctsurg_file(
      path, "trajectory", 1, provenance,
      [&](h5::Group& root) {
        h5::Group g = root.create_group("trajectory");
        g.set_attribute("scenario", t.scenario);
        g.set_attribute("model", t.model);
        g.set_attribute("surface_file", t.surface_file);
        g.set_attribute("surface_sha256", t.surface_sha256);
        g.set_attribute("dt_s", t.dt_s);
        g.set_attribute("frames", static_cast<int64_t>(nf));
        g.set_attribute("vertices", static_cast<int64_t>(nv));
        g.set_attribute("frame", std::string("LPS"));
        g.set_attribute("units", std::string("mm"));
        const std::array<uint64_t, 1> f1{nf};
        g.write_dataset("time", t.time, f1);
        h5::Group s = g.create_group("surface");
        const std::array<uint64_t, 2> v3{nv, 3};
        const std::array<uint64_t, 3> fv3{nf, nv, 3};
        s.write_dataset("rest_vertices", t.rest_vertices, v3);
        s.write_dataset("vertices", t.vertices, fv3);
        s.write_dataset("topology_of_frame", t.topology_of_frame, f1);
        if (!t.closing_triangles.empty()) {
          s.write_dataset("closing_triangles", t.closing_triangles, std::array<uint64_t, 1>{t.closing_triangles.size()});
        }
        if (!t.vertex_region.empty()) s.write_dataset("vertex_region", t.vertex_region, std::array<uint64_t, 2>{nf, nv});
        h5::Group topo = s.create_group("topologies");
        for (size_t k = 0; k < t.topologies.size(); ++k) {
          const std::array<uint64_t, 2> t3{t.topologies[k].size() / 3, 3};
          topo.write_dataset(std::to_string(k), t.topologies[k], t3);
        }
        h5::Group m = g.create_group("metrics");
        for (const auto& metric : t.metrics) {
          m.write_dataset(metric.name, metric.values, f1);
        }
        // The order and units as attributes of the metrics group, read back with the values.
        std::vector<std::string> names;
        for (const auto& metric : t.metrics) {
          m.set_attribute(metric.name + "_units", metric.units);
          names.push_back(metric.name);
        }
        m.set_attribute("names", join(names, ';'));
        h5::Group tools = g.create_group("tools");
        tools.set_attribute("kinds", join(t.sphere_kinds, ';'));
        const std::array<uint64_t, 3> s4{nf, ns, 4}, b7{nf, nb, 7};
        tools.write_dataset("spheres", t.spheres, s4);
        tools.write_dataset("blades", t.blades, b7);
        if (!t.instruments.empty()) {
          h5::Group ig = tools.create_group("instruments");
          for (size_t k = 0; k < t.instruments.size(); ++k) {
            const TrajectoryInstrument& ins = t.instruments[k];
            h5::Group one = ig.create_group(std::to_string(k));
            one.set_attribute("name", ins.name);
            one.write_dataset("vertices", ins.vertices, std::array<uint64_t, 2>{ins.vertices.size() / 3, 3});
            one.write_dataset("triangles", ins.triangles, std::array<uint64_t, 2>{ins.triangles.size() / 3, 3});
          }
          tools.write_dataset("instrument_poses", t.instrument_poses, std::array<uint64_t, 3>{nf, t.instruments.size(), 8});
        }
        if (!t.sphere_loads.empty()) {
          tools.write_dataset("sphere_loads", t.sphere_loads, std::array<uint64_t, 3>{nf, t.sphere_kinds.size(), 7});
        }
        if (!t.stitches.empty()) {
          tools.write_dataset("stitches", t.stitches, std::array<uint64_t, 3>{nf, static_cast<uint64_t>(t.stitch_count()), 7});
        }
        if (np > 0) {
          h5::Group p = g.create_group("particles");
          const std::array<uint64_t, 2> p3{np, 3};
          const std::array<uint64_t, 3> fp3{nf, np, 3};
          p.write_dataset("rest_positions", t.rest_particles, p3);
          p.write_dataset("positions", t.particles, fp3);
          if (!t.elements.empty()) {
            p.write_dataset("elements", t.elements,
                            std::array<uint64_t, 2>{static_cast<uint64_t>(t.element_count()), static_cast<uint64_t>(t.element_nodes)});
          }
        }
      },
      trajectory_xdmf(path.filename().string(), t));
}

Trajectory read_trajectory_file(const std::filesystem::path& path) {
  const std::string file = path.string();
  const h5::File f = open_ctsurg_file(path, "trajectory");
  const h5::Group g = f.root().open_group("trajectory");
  Trajectory t;
  t.scenario = g.string_attribute("scenario");
  t.model = g.string_attribute("model");
  t.surface_file = g.string_attribute("surface_file");
  t.surface_sha256 = g.string_attribute("surface_sha256");
  t.dt_s = g.double_attribute("dt_s");
  std::vector<uint64_t> shape;
  const auto expect = [&](const h5::Group& grp, const std::string& name, std::initializer_list<int64_t> dims) {
    bool ok = shape.size() == dims.size();
    size_t i = 0;
    for (const int64_t d : dims) {
      if (ok && d >= 0 && shape[i] != static_cast<uint64_t>(d)) ok = false;
      ++i;
    }
    if (!ok) throw InputError(file, grp.path() + "/" + name, "unexpected shape");
  };
  t.time = g.read_dataset<double>("time", &shape);
  expect(g, "time", {-1});
  const int64_t nf = static_cast<int64_t>(shape[0]);
  const h5::Group s = g.open_group("surface");
  t.rest_vertices = s.read_dataset<float>("rest_vertices", &shape);
  expect(s, "rest_vertices", {-1, 3});
  const int64_t nv = static_cast<int64_t>(shape[0]);
  t.vertices = s.read_dataset<float>("vertices", &shape);
  expect(s, "vertices", {nf, nv, 3});
  t.topology_of_frame = s.read_dataset<int32_t>("topology_of_frame", &shape);
  expect(s, "topology_of_frame", {nf});
  const h5::Group topo = s.open_group("topologies");
  for (int64_t k = 0; topo.has(std::to_string(k)); ++k) {
    t.topologies.push_back(topo.read_dataset<uint32_t>(std::to_string(k), &shape));
    expect(topo, std::to_string(k), {-1, 3});
  }
  if (s.has("closing_triangles")) {  // optional: files from before hole filling have none
    t.closing_triangles = s.read_dataset<int64_t>("closing_triangles", &shape);
    expect(s, "closing_triangles", {static_cast<int64_t>(t.topologies.size())});
  }
  if (s.has("vertex_region")) {  // optional: only runs with an FEM local region have it
    t.vertex_region = s.read_dataset<uint8_t>("vertex_region", &shape);
    expect(s, "vertex_region", {nf, nv});
  }
  // The metrics in the order written (/trajectory/metrics@names), each with its units attribute.
  const h5::Group m = g.open_group("metrics");
  for (const auto& name : split(m.string_attribute("names"), ';')) {
    TrajectoryMetric metric;
    metric.name = name;
    metric.values = m.read_dataset<double>(name, &shape);
    expect(m, name, {nf});
    metric.units = m.string_attribute(name + "_units");
    t.metrics.push_back(std::move(metric));
  }
  const h5::Group tools = g.open_group("tools");
  t.sphere_kinds = split(tools.string_attribute("kinds"), ';');
  t.spheres = tools.read_dataset<double>("spheres", &shape);
  expect(tools, "spheres", {nf, static_cast<int64_t>(t.sphere_kinds.size()), 4});
  t.blades = tools.read_dataset<double>("blades", &shape);
  expect(tools, "blades", {nf, -1, 7});
  if (tools.has("instruments")) {
    const h5::Group ig = tools.open_group("instruments");
    for (int64_t k = 0; ig.has(std::to_string(k)); ++k) {
      if (k >= 1024) throw InputError(file, "/trajectory/tools/instruments", "more than 1024 instruments");
      const h5::Group one = ig.open_group(std::to_string(k));
      TrajectoryInstrument ins;
      ins.name = one.string_attribute("name");
      ins.vertices = one.read_dataset<float>("vertices", &shape);
      expect(one, "vertices", {-1, 3});
      ins.triangles = one.read_dataset<uint32_t>("triangles", &shape);
      expect(one, "triangles", {-1, 3});
      t.instruments.push_back(std::move(ins));
    }
    t.instrument_poses = tools.read_dataset<double>("instrument_poses", &shape);
    expect(tools, "instrument_poses", {nf, static_cast<int64_t>(t.instruments.size()), 8});
  }
  if (tools.has("sphere_loads")) {  // optional: files from before tool loads, or without a measured one, have none
    t.sphere_loads = tools.read_dataset<double>("sphere_loads", &shape);
    expect(tools, "sphere_loads", {nf, static_cast<int64_t>(t.sphere_kinds.size()), 7});
  }
  if (tools.has("stitches")) {  // optional: files from before sutures have none
    t.stitches = tools.read_dataset<double>("stitches", &shape);
    expect(tools, "stitches", {nf, -1, 7});
  }
  if (g.has("particles")) {
    const h5::Group p = g.open_group("particles");
    t.rest_particles = p.read_dataset<float>("rest_positions", &shape);
    expect(p, "rest_positions", {-1, 3});
    const int64_t np = static_cast<int64_t>(shape[0]);
    t.particles = p.read_dataset<float>("positions", &shape);
    expect(p, "positions", {nf, np, 3});
    if (p.has("elements")) {  // optional: FEM runs (files from before it, and other models, have none)
      t.elements = p.read_dataset<int32_t>("elements", &shape);
      expect(p, "elements", {-1, -1});
      t.element_nodes = static_cast<int32_t>(std::min<uint64_t>(shape[1], 1000));
    }
  }
  validate_trajectory(t, file);
  return t;
}

}  // namespace ctsurg
