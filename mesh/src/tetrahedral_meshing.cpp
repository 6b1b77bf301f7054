// The only source file that includes CGAL (Mesh_3): labelled image in, plain arrays out.
#include "ctsurg/mesh/tetrahedral_meshing.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/elapsed_seconds.h"
#include "ctsurg/mesh/tet_mesh_quality.h"

// GCC 12 reports false -Wmaybe-uninitialized in boost::optional inside CGAL's Mesh_3 (the
// sanitizer build's inlining exposes them).
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Image_3.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Random.h>
#include <CGAL/exude_mesh_3.h>
#include <CGAL/lloyd_optimize_mesh_3.h>
#include <CGAL/make_mesh_3.h>
#include <CGAL/odt_optimize_mesh_3.h>
#include <CGAL/perturb_mesh_3.h>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <map>
#include <numbers>
#include <set>

namespace ctsurg {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using MeshDomain = CGAL::Labeled_mesh_domain_3<K>;
// Sequential_tag: Mesh_3's parallel mode is not deterministic.
using Tr = CGAL::Mesh_triangulation_3<MeshDomain, CGAL::Default, CGAL::Sequential_tag>::type;
using C3t3 = CGAL::Mesh_complex_3_in_triangulation_3<Tr>;
using MeshCriteria = CGAL::Mesh_criteria_3<Tr>;
namespace params = CGAL::parameters;

// Voxels to mesh: requested labels kept, everything else 0, cropped to their bounding box plus a
// margin of `kPad` empty voxels so the surface closes inside the image (CGAL clips the domain at the
// image's bounding box). `offset` is the crop's first voxel in the source lattice (may be negative).
constexpr int64_t kPad = 2;

struct Cropped {
  std::array<int64_t, 3> dims{}, offset{};
  std::vector<uint16_t> voxels;
  int64_t count = 0;  // voxels with a requested label
};

bool wanted(uint16_t v, const std::vector<uint16_t>& labels) {
  return v != 0 && (labels.empty() || std::find(labels.begin(), labels.end(), v) != labels.end());
}

Cropped crop_labels(const Volume<uint16_t>& labels, const std::vector<uint16_t>& wanted_labels) {
  const auto& d = labels.geometry.dims;
  std::array<int64_t, 3> lo{d[0], d[1], d[2]}, hi{-1, -1, -1};
  Cropped c;
  for (int64_t k = 0; k < d[2]; ++k)
    for (int64_t j = 0; j < d[1]; ++j)
      for (int64_t i = 0; i < d[0]; ++i) {
        if (!wanted(labels(i, j, k), wanted_labels)) continue;
        ++c.count;
        const std::array<int64_t, 3> p{i, j, k};
        for (std::size_t a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
      }
  if (c.count == 0) return c;
  for (std::size_t a = 0; a < 3; ++a) {
    c.offset[a] = lo[a] - kPad;
    c.dims[a] = hi[a] - lo[a] + 1 + 2 * kPad;
  }
  c.voxels.assign(static_cast<std::size_t>(c.dims[0] * c.dims[1] * c.dims[2]), 0);
  for (int64_t k = kPad; k < c.dims[2] - kPad; ++k)
    for (int64_t j = kPad; j < c.dims[1] - kPad; ++j)
      for (int64_t i = kPad; i < c.dims[0] - kPad; ++i) {
        const uint16_t v = labels(i + c.offset[0], j + c.offset[1], k + c.offset[2]);
        if (wanted(v, wanted_labels)) c.voxels[static_cast<std::size_t>(i + c.dims[0] * (j + c.dims[1] * k))] = v;
      }
  return c;
}

// Voxel faces between a wanted voxel and anything else, mm^2 (the staircase area: an overestimate of
// the smooth surface by up to 1.5x, fine for a guard).
double staircase_area_mm2(const Volume<uint16_t>& labels, const std::vector<uint16_t>& wanted_labels) {
  const auto& g = labels.geometry;
  const auto& d = g.dims;
  const Eigen::Matrix3d m = g.index_to_world_matrix();
  const std::array<double, 3> face{m.col(1).cross(m.col(2)).norm(), m.col(0).cross(m.col(2)).norm(),
                                   m.col(0).cross(m.col(1)).norm()};
  double area = 0.0;
  for (int64_t k = 0; k < d[2]; ++k)
    for (int64_t j = 0; j < d[1]; ++j)
      for (int64_t i = 0; i < d[0]; ++i) {
        const uint16_t v = labels(i, j, k);
        if (!wanted(v, wanted_labels)) continue;
        const std::array<int64_t, 3> p{i, j, k};
        for (std::size_t a = 0; a < 3; ++a)
          for (const int64_t s : {-1, 1}) {
            std::array<int64_t, 3> q = p;
            q[a] += s;
            const bool inside = q[a] >= 0 && q[a] < d[a];
            if (!inside || labels(q[0], q[1], q[2]) != v) area += face[a];
          }
      }
  return area;
}

CGAL::Image_3 make_image(const Cropped& c, const Eigen::Vector3d& spacing) {
  _image* im = _createImage(static_cast<std::size_t>(c.dims[0]), static_cast<std::size_t>(c.dims[1]),
                            static_cast<std::size_t>(c.dims[2]), 1, spacing[0], spacing[1], spacing[2],
                            sizeof(uint16_t), WK_FIXED, SGN_UNSIGNED);
  if (im == nullptr) throw RuntimeError("CGAL image allocation failed");
  std::memcpy(im->data, c.voxels.data(), c.voxels.size() * sizeof(uint16_t));
  return CGAL::Image_3(im);  // owns im
}

const char* optimiser_name(TetOptimiser o) {
  switch (o) {
    case TetOptimiser::odt: return "odt";
    case TetOptimiser::lloyd: return "lloyd";
    case TetOptimiser::none: break;
  }
  return "none";
}

// (a, b, c) with the normal (b - a) x (c - a) pointing away from vertex `i` of a positively oriented
// cell: (a, b, c, i) must be an odd permutation of (0, 1, 2, 3).
std::array<int, 3> outward_facet(int i) {
  static constexpr int table[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  return {table[i][0], table[i][1], table[i][2]};
}

}  // namespace

void validate_tet_meshing_options(const TetMeshingOptions& o) {
  const auto positive = [](double v, const char* name) {
    if (!std::isfinite(v) || v <= 0.0) throw InputError(name, "", "must be a positive number of mm, got " + std::to_string(v));
  };
  positive(o.cell_size_mm, "--cell-size");
  positive(o.facet_size_mm, "--facet-size");
  positive(o.facet_distance_mm, "--facet-distance");
  if (!std::isfinite(o.radius_edge_ratio) || o.radius_edge_ratio < 1.0) {
    throw InputError("--radius-edge", "", "must be at least 1 (2 or more guarantees termination), got " +
                                              std::to_string(o.radius_edge_ratio));
  }
  if (!std::isfinite(o.facet_angle_deg) || o.facet_angle_deg <= 0.0 || o.facet_angle_deg > 30.0) {
    throw InputError("--facet-angle", "", "must be in (0, 30] degrees (Mesh_3 terminates up to 30), got " +
                                              std::to_string(o.facet_angle_deg));
  }
  if (!std::isfinite(o.sliver_bound_deg) || o.sliver_bound_deg < 0.0 || o.sliver_bound_deg >= 70.0) {
    throw InputError("--sliver-bound", "", "must be in [0, 70) degrees, got " + std::to_string(o.sliver_bound_deg));
  }
  if (o.optimiser_iterations < 1) throw InputError("--optimiser-iterations", "", "must be at least 1");
}

int64_t estimate_tet_count(double meshed_volume_mm3, double surface_area_mm2, const TetMeshingOptions& o) {
  // Volume of the regular tet with circumradius r: 8 sqrt(3) / 27 r^3.
  const auto regular = [](double r) { return 8.0 * std::sqrt(3.0) / 27.0 * r * r * r; };
  const double interior = meshed_volume_mm3 / regular(0.7 * o.cell_size_mm);
  // Boundary facets: the area over an equilateral triangle of circumradius 0.7 x facet size (or of
  // the size the facet distance allows on a surface curved like a voxel, whichever is smaller); about
  // three tets behind each.
  const double f = std::min(0.7 * o.facet_size_mm, 4.0 * o.facet_distance_mm + 0.5);
  const double facets = surface_area_mm2 / (3.0 * std::sqrt(3.0) / 4.0 * f * f);
  const double total = interior + 3.0 * facets;
  return total > 9e18 ? INT64_MAX : static_cast<int64_t>(std::ceil(total));
}

TetMesh tetrahedral_mesh(const Volume<uint16_t>& labels, const TetMeshingOptions& o, const std::string& source_name) {
  validate_tet_meshing_options(o);
  const ImageGeometry& g = labels.geometry;
  const Cropped c = crop_labels(labels, o.labels);
  if (c.count == 0) {
    std::string which = "any non-zero label";
    if (!o.labels.empty()) {
      which = "label";
      for (std::size_t i = 0; i < o.labels.size(); ++i) which += (i ? "," : " ") + std::to_string(o.labels[i]);
    }
    throw InputError(source_name, "labels", "no voxel has " + which + ": nothing to mesh");
  }
  const auto start = std::chrono::steady_clock::now();

  // Every random choice from the seed: the domain's (initial points), and the default generator used
  // by the initial-point construction on the image.
  CGAL::get_default_random() = CGAL::Random(static_cast<unsigned>(o.seed));
  CGAL::Random rng(static_cast<unsigned>(o.seed));
  const CGAL::Image_3 image = make_image(c, g.spacing);
  const MeshDomain domain = MeshDomain::create_labeled_image_mesh_domain(image, params::p_rng = &rng);
  const MeshCriteria criteria(params::facet_angle = o.facet_angle_deg, params::facet_size = o.facet_size_mm,
                              params::facet_distance = o.facet_distance_mm,
                              params::cell_radius_edge_ratio = o.radius_edge_ratio,
                              params::cell_size = o.cell_size_mm);
  C3t3 c3t3 = CGAL::make_mesh_3<C3t3>(domain, criteria, params::no_perturb(), params::no_exude(),
                                      params::no_odt(), params::no_lloyd());
  spdlog::info("tetmesh: Delaunay refinement {} cells in {:.2f} s", c3t3.number_of_cells_in_complex(),
               seconds_since(start));
  // Optimisers and sliver removal without time limits: a time limit would make the result depend
  // on the machine's speed.
  auto step = std::chrono::steady_clock::now();
  if (o.optimiser == TetOptimiser::odt) {
    CGAL::odt_optimize_mesh_3(c3t3, domain, params::time_limit = 0,
                              params::max_iteration_number = o.optimiser_iterations);
  } else if (o.optimiser == TetOptimiser::lloyd) {
    CGAL::lloyd_optimize_mesh_3(c3t3, domain, params::time_limit = 0,
                                params::max_iteration_number = o.optimiser_iterations);
  }
  if (o.optimiser != TetOptimiser::none) {
    spdlog::info("tetmesh: {} smoothing ({} iterations) in {:.2f} s", optimiser_name(o.optimiser),
                 o.optimiser_iterations, seconds_since(step));
  }
  step = std::chrono::steady_clock::now();
  CGAL::perturb_mesh_3(c3t3, domain, params::time_limit = 0, params::sliver_bound = o.sliver_bound_deg);
  CGAL::exude_mesh_3(c3t3, params::time_limit = 0, params::sliver_bound = o.sliver_bound_deg);
  spdlog::info("tetmesh: sliver perturbation and exudation (bound {} deg) in {:.2f} s", o.sliver_bound_deg,
               seconds_since(step));
  if (c3t3.number_of_cells_in_complex() == 0) {
    throw RuntimeError(source_name + ": CGAL Mesh_3 produced no tetrahedra (criteria too coarse for the labelled region?)");
  }

  // Plain arrays. Nodes are numbered in order of first use by the cells in the complex (the
  // triangulation's deterministic storage order). CGAL coordinates are index x spacing of the crop.
  TetMesh m;
  std::map<Tr::Vertex_handle, int32_t> index;
  const auto point = c3t3.triangulation().geom_traits().construct_point_3_object();
  const Eigen::Matrix3d to_world = g.index_to_world_matrix();
  const bool mirrored = to_world.determinant() < 0.0;
  const Eigen::Vector3d offset(static_cast<double>(c.offset[0]), static_cast<double>(c.offset[1]),
                               static_cast<double>(c.offset[2]));
  const auto node_of = [&](Tr::Vertex_handle v) {
    const auto [it, fresh] = index.try_emplace(v, static_cast<int32_t>(index.size()));
    if (fresh) {
      const auto p = point(v->point());
      const Eigen::Vector3d ijk = Eigen::Vector3d(p.x() / g.spacing[0], p.y() / g.spacing[1], p.z() / g.spacing[2]) + offset;
      const Eigen::Vector3d w = g.index_to_world(ijk);
      m.nodes.insert(m.nodes.end(), {w[0], w[1], w[2]});
    }
    return it->second;
  };
  for (auto cit = c3t3.cells_in_complex_begin(); cit != c3t3.cells_in_complex_end(); ++cit) {
    // CGAL cells are positively oriented in CGAL's (index x spacing) frame; a mirrored lattice flips them.
    std::array<int32_t, 4> t{node_of(cit->vertex(0)), node_of(cit->vertex(1)), node_of(cit->vertex(2)),
                             node_of(cit->vertex(3))};
    if (mirrored) std::swap(t[2], t[3]);
    m.tets.insert(m.tets.end(), t.begin(), t.end());
    m.tet_labels.push_back(static_cast<uint16_t>(c3t3.subdomain_index(cit)));
  }
  for (auto fit = c3t3.facets_in_complex_begin(); fit != c3t3.facets_in_complex_end(); ++fit) {
    Tr::Cell_handle cell = fit->first;
    int i = fit->second;
    Tr::Cell_handle other = cell->neighbor(i);
    const auto label_of = [&](Tr::Cell_handle h) {
      return c3t3.is_in_complex(h) ? static_cast<uint16_t>(c3t3.subdomain_index(h)) : uint16_t{0};
    };
    uint16_t in = label_of(cell), out = label_of(other);
    // Inside is the labelled side; on an interface, the smaller label.
    if (in == 0 || (out != 0 && out < in)) {
      const int j = other->index(cell);
      cell = other;
      i = j;
      std::swap(in, out);
    }
    const auto f = outward_facet(i);
    std::array<int32_t, 3> tri{node_of(cell->vertex(f[0])), node_of(cell->vertex(f[1])), node_of(cell->vertex(f[2]))};
    if (mirrored) std::swap(tri[1], tri[2]);
    m.boundary_faces.insert(m.boundary_faces.end(), tri.begin(), tri.end());
    m.face_labels.insert(m.face_labels.end(), {in, out});
  }

  m.mask_volume_mm3 = static_cast<double>(c.count) * g.voxel_volume_mm3();
  m.seed = o.seed;
  nlohmann::json criteria_json = {{"cell_size_mm", o.cell_size_mm},
                                  {"facet_size_mm", o.facet_size_mm},
                                  {"facet_distance_mm", o.facet_distance_mm},
                                  {"radius_edge_ratio", o.radius_edge_ratio},
                                  {"facet_angle_deg", o.facet_angle_deg},
                                  {"optimiser", optimiser_name(o.optimiser)},
                                  {"optimiser_iterations", o.optimiser_iterations},
                                  {"sliver_bound_deg", o.sliver_bound_deg},
                                  {"labels", o.labels}};
  m.criteria = criteria_json.dump();
  m.quality = tet_mesh_quality(m.nodes, m.tets);
  return m;
}

double labelled_volume_mm3(const Volume<uint16_t>& labels, const std::vector<uint16_t>& wanted_labels) {
  int64_t n = 0;
  for (const uint16_t v : labels.voxels) n += wanted(v, wanted_labels);
  return static_cast<double>(n) * labels.geometry.voxel_volume_mm3();
}

double labelled_surface_area_mm2(const Volume<uint16_t>& labels, const std::vector<uint16_t>& wanted_labels) {
  return staircase_area_mm2(labels, wanted_labels);
}

}  // namespace ctsurg
