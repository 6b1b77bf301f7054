#include "ctsurg/sim/scenario/scenario_engine.h"

#include "ctsurg/core/centerline_file.h"
#include "ctsurg/core/error.h"
#include "ctsurg/core/occupancy_grid_file.h"
#include "ctsurg/core/surface_mesh_file.h"
#include "ctsurg/core/tet_mesh_file.h"
#include "ctsurg/sim/base/backend.h"
#include "ctsurg/sim/base/fixed_regions.h"
#include "ctsurg/sim/fem/fem_contact.h"
#include "ctsurg/sim/fem/fem_engine.h"
#include "ctsurg/sim/fem/fem_explicit_dynamics.h"
#include "ctsurg/sim/fem/kernels/fem_quadratic_element_impl.h"
#include "ctsurg/sim/scenario/scenario_model.h"
#include "ctsurg/sim/springs/spring_calibration.h"
#include "ctsurg/sim/springs/spring_engine.h"
#include "ctsurg/sim/surface/embedded_surface.h"
#include "ctsurg/sim/surface/tet_embedding.h"
#include "scenario_material.h"
#include "ctsurg/sim/vessel/vessel_engine.h"
#include "rest_bounds.h"

#include <cmath>
#include <optional>

namespace ctsurg::sim {
namespace {

// The run's local origin: the whole-millimetre point nearest `centre` (LPS mm).
Vec3 local_origin(const Vec3& centre) { return {std::round(centre[0]), std::round(centre[1]), std::round(centre[2])}; }

// The centroid of tet e of `mesh` (the mesh's frame, mm).
Vec3 tet_centroid(const TetMesh& mesh, size_t e) {
  Vec3 x{0, 0, 0};
  for (size_t a = 0; a < 3; ++a)
    for (size_t k = 0; k < 4; ++k) x[a] += 0.25 * mesh.nodes[3 * static_cast<size_t>(mesh.tets[4 * e + k]) + a];
  return x;
}

// material.labels against the labels the model's elements carry (`labels`, one per tet or particle):
// label -> index into s.label_materials (65,536 entries, -1 = none). Every element's label needs a
// material and every material's label must be there; `owner` names what carries them ("the tet mesh"),
// `path` its file. Empty when the scenario gives no labels.
std::vector<int32_t> label_material_index(const Scenario& s, const std::vector<uint16_t>& labels, const std::string& owner,
                                          const std::string& path) {
  if (s.label_materials.empty()) return {};
  const std::string sfile = s.file.string();
  std::vector<uint8_t> present(65536, 0);
  for (const uint16_t l : labels) present[l] = 1;
  std::string in_model;
  for (size_t l = 0; l < present.size(); ++l)
    if (present[l]) in_model += (in_model.empty() ? "" : ", ") + std::to_string(l);
  std::vector<int32_t> index(65536, -1);
  for (size_t m = 0; m < s.label_materials.size(); ++m) {
    const LabelMaterial& lm = s.label_materials[m];
    if (!present[lm.label]) {
      throw InputError(sfile, lm.field, owner + " " + path + " has no label " + std::to_string(lm.label) + " (its labels: " + in_model + ")");
    }
    index[lm.label] = static_cast<int32_t>(m);
  }
  for (size_t l = 0; l < present.size(); ++l) {
    if (present[l] && index[l] < 0) {
      throw InputError(sfile, "material.labels", owner + "'s label " + std::to_string(l) + " has no material (its labels: " + in_model +
                                                     "); give every label one");
    }
  }
  return index;
}

// material.inclusions: the elements whose centre (centre(e), local frame) lies in inclusion k's sphere
// take material first + k, a later inclusion over an earlier one. element_material (#count) is filled
// with 0 first when empty. The sphere's at_fraction refers to `lps_bounds`; `origin` is the local
// frame's. InputError naming the inclusion when its sphere holds no element ("holds no <element> of
// <owner>").
void apply_inclusions(const Scenario& s, int32_t first, size_t count, const std::function<Vec3(size_t)>& centre,
                      const RestBounds& lps_bounds, const Vec3& origin, const std::string& element, const std::string& owner,
                      std::vector<int32_t>& element_material, const std::function<void(const std::string&)>& note) {
  for (size_t k = 0; k < s.inclusions.size(); ++k) {
    const InclusionMaterial& inc = s.inclusions[k];
    Vec3 c = inc.centre.kind == PointSpec::Kind::at_fraction ? lps_bounds.at(inc.centre.value) : inc.centre.value;  // LPS
    for (size_t a = 0; a < 3; ++a) c[a] -= origin[a];
    const int32_t id = first + static_cast<int32_t>(k);
    if (element_material.empty()) element_material.assign(count, 0);
    int64_t taken = 0;
    for (size_t e = 0; e < count; ++e) {
      const Vec3 x = centre(e);
      double d2 = 0;
      for (size_t a = 0; a < 3; ++a) d2 += (x[a] - c[a]) * (x[a] - c[a]);
      if (d2 < inc.radius_mm * inc.radius_mm) element_material[e] = id, ++taken;
    }
    if (taken == 0) {
      throw InputError(s.file.string(), inc.field + ".sphere",
                       "holds no " + element + " of " + owner + " (centre LPS " + std::to_string(c[0] + origin[0]) + ", " +
                           std::to_string(c[1] + origin[1]) + ", " + std::to_string(c[2] + origin[2]) + " mm, radius " +
                           std::to_string(inc.radius_mm) + " mm)");
    }
    if (note) note(inc.field + ": " + std::to_string(taken) + " " + element + "s of " + inc.material.name);
  }
}

// What the scenario's fixed regions hold: the whole particles (or nodes; increasing ids) and, for
// regions that fix some axes only, single components (3 id + axis, increasing; not of whole ones).
struct Held {
  std::vector<int32_t> whole;
  std::vector<int32_t> components;
};

// The scenario's fixed regions over the rest positions `rest` (#P x 3, local frame: LPS minus
// `origin`); `bounds`: the box that box_fraction refers to; `by_label` selects a label's particles.
// InputError naming "fixed[r]" when a region selects nothing.
Held fixed_particles(const Scenario& s, const std::vector<Real>& rest, const RestBounds& bounds, const Vec3& origin,
                     const std::function<std::vector<int32_t>(uint16_t)>& by_label) {
  std::vector<uint8_t> axes(rest.size() / 3, 0);
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
    for (const int32_t id : ids) axes[static_cast<size_t>(id)] |= f.axes;
  }
  Held held;
  for (size_t i = 0; i < axes.size(); ++i) {
    if (axes[i] == 7) {
      held.whole.push_back(static_cast<int32_t>(i));
      continue;
    }
    for (int a = 0; a < 3; ++a)
      if (axes[i] >> a & 1) held.components.push_back(static_cast<int32_t>(3 * i) + a);
  }
  return held;
}

// The options every engine takes, from the scenario (the step is the engine's own business: the FEM's
// is checked against its critical step first).
EngineOptions engine_options(const Scenario& s, const std::function<void(const std::string&)>& note) {
  EngineOptions o;
  o.safety_factor = s.safety_factor;
  o.mass_damping = s.damping_per_s;
  o.gravity = s.gravity;
  o.threads = s.threads;
  o.density = s.material.density;
  o.where = s.file.string();
  o.note = note;
  return o;
}

// The surface file, and its vertices moved into the local frame (in double before rounding to float).
struct LocalSurface {
  SurfaceMesh mesh;                // vertices and lattice in the local frame
  std::vector<float> lps_vertices; // as read
};

LocalSurface read_local_surface(const Scenario& s, const Vec3& origin) {
  LocalSurface r;
  r.mesh = read_surface_mesh_file(s.surface);
  r.lps_vertices = r.mesh.vertices;
  r.mesh.lattice.origin -= Eigen::Vector3d(origin[0], origin[1], origin[2]);
  for (size_t i = 0; i < r.mesh.vertices.size(); ++i) {
    r.mesh.vertices[i] = static_cast<float>(static_cast<double>(r.mesh.vertices[i]) - origin[i % 3]);
  }
  return r;
}

EmbeddedSurface embed_in_tets(const SurfaceMesh& surface, const TetMesh& mesh, const std::function<void(const std::string&)>& note) {
  TetEmbeddingStats st;
  SurfaceCoupling coupling = embed_surface_in_tets(surface.vertices, mesh, 10.0, &st);
  if (note) {
    note("surface: " + std::to_string(st.inside) + " vertices inside tets, " + std::to_string(st.outside) + " outside (at most " +
         std::to_string(st.max_outside_mm) + " mm)");
  }
  return EmbeddedSurface(std::move(coupling), surface.triangles);
}

ScenarioEngine spring_engine(const Scenario& s, Backend backend, const std::function<void(const std::string&)>& note) {
  const std::string sfile = s.file.string();
  const ModelInputs in = model_inputs(s);
  // The grid's centre sets the local frame, for every spring model (explicit springs from a tet mesh too).
  OccupancyGrid grid = read_occupancy_grid_file(s.grid);
  const auto& dims = grid.occupancy.geometry.dims;
  const Eigen::Vector3d centre = grid.occupancy.geometry.index_to_world(
      0.5 * Eigen::Vector3d(static_cast<double>(dims[0] - 1), static_cast<double>(dims[1] - 1), static_cast<double>(dims[2] - 1)));
  const Vec3 origin = local_origin({centre[0], centre[1], centre[2]});
  const Eigen::Vector3d shift(origin[0], origin[1], origin[2]);
  for (ImageGeometry* g : {&grid.occupancy.geometry, &grid.fraction.geometry, &grid.label.geometry, &grid.mask.geometry}) {
    g->origin -= shift;
  }
  std::optional<SpringGridModel> grid_model;
  std::optional<TetMesh> tetmesh;
  SpringModel model;
  // Each organ its own material (material.labels, material.inclusions; explicit springs only, parsed so):
  // the labels' materials (or the section's) and then the inclusions', indexed per tet or grid cell.
  const bool per_element = !s.label_materials.empty() || !s.inclusions.empty();
  std::vector<Material> materials;
  for (const LabelMaterial& lm : s.label_materials) materials.push_back(lm.material);
  if (materials.empty()) materials.push_back(s.material);
  const int32_t first_inclusion = static_cast<int32_t>(materials.size());
  for (const InclusionMaterial& inc : s.inclusions) materials.push_back(inc.material);
  if (!in.tetmesh) {
    grid_model = build_spring_grid_model(grid, calibrated_grid_material(materials.front(), grid.occupancy.geometry, s.mass_from_fraction));
    if (s.model == ModelKind::spring_grid) {
      model = *grid_model;
    } else if (!per_element) {
      model = explicit_model_from_grid(*grid_model);
    } else {
      // A particle takes the material of its cell's label (/grid/label: the cell's dominant tissue).
      const int32_t n = grid_model->particle_count();
      std::vector<uint16_t> particle_label(static_cast<size_t>(n), 0);
      if (!s.label_materials.empty()) {
        if (grid.label.geometry.dims != grid.occupancy.geometry.dims) {
          throw InputError(sfile, "material.labels", "the occupancy grid " + s.grid.string() + " has no /grid/label on its lattice");
        }
        for (int32_t p = 0; p < n; ++p) {
          particle_label[static_cast<size_t>(p)] = grid.label.voxels[static_cast<size_t>(grid_model->cells[static_cast<size_t>(p)])];
        }
      }
      const std::vector<int32_t> label_index = label_material_index(s, particle_label, "the occupancy grid", s.grid.string());
      std::vector<int32_t> particle_material;
      if (!label_index.empty()) {
        particle_material.reserve(static_cast<size_t>(n));
        for (const uint16_t l : particle_label) particle_material.push_back(label_index[l]);
      }
      const std::vector<Real>& rest = grid_model->rest_positions;
      RestBounds lps = bounds_of(rest);
      for (size_t a = 0; a < 3; ++a) lps.lo[a] += origin[a], lps.hi[a] += origin[a];
      apply_inclusions(s, first_inclusion, static_cast<size_t>(n),
                       [&](size_t p) { return Vec3{rest[3 * p], rest[3 * p + 1], rest[3 * p + 2]}; }, lps, origin, "cell",
                       "the occupancy grid", particle_material, note);
      model = calibrated_grid_spring_model(*grid_model, materials, particle_material, materials.front().density);
    }
  } else {
    tetmesh = read_tet_mesh_file(s.tetmesh);
    const RestBounds lps = bounds_of(tetmesh->nodes);
    for (size_t i = 0; i < tetmesh->nodes.size(); ++i) tetmesh->nodes[i] -= origin[i % 3];
    if (!per_element) {
      model = calibrated_tet_spring_model(*tetmesh, s.material);
    } else {
      const std::vector<int32_t> label_index = label_material_index(s, tetmesh->tet_labels, "the tet mesh", s.tetmesh.string());
      std::vector<int32_t> tet_material;
      if (!label_index.empty()) {
        tet_material.reserve(tetmesh->tet_labels.size());
        for (const uint16_t l : tetmesh->tet_labels) tet_material.push_back(label_index[l]);
      }
      apply_inclusions(s, first_inclusion, tetmesh->tet_labels.size(), [&](size_t e) { return tet_centroid(*tetmesh, e); }, lps, origin,
                       "tet", "the tet mesh", tet_material, note);
      model = calibrated_tet_spring_model(*tetmesh, materials, tet_material);
    }
  }
  const std::vector<Real>& rest = std::visit([](const auto& m) -> const std::vector<Real>& { return m.rest_positions; }, model);
  ParticleState state = std::visit([](const auto& m) { return m.make_state(); }, model);
  const Held held = fixed_particles(s, rest, bounds_of(rest), origin, [&](uint16_t label) {
    return grid_model ? particles_with_label(*grid_model, grid.label, label) : nodes_with_label(*tetmesh, label);
  });
  fix_particles(state, held.whole);

  ScenarioEngine r;
  EmbeddedSurface surface;
  if (in.surface) {
    LocalSurface local = read_local_surface(s, origin);
    r.surface_lps_vertices = std::move(local.lps_vertices);
    if (grid_model) {
      surface = EmbeddedSurface(couple_surface(local.mesh, grid_model->lattice, grid_model->cells, s.coupling), local.mesh.triangles);
    } else {
      surface = embed_in_tets(local.mesh, *tetmesh, note);
    }
    surface.set_close_cuts(s.close_cuts);
  }
  if (backend == Backend::cuda) {
    for (const auto& t : s.tools) {
      switch (t.acts()) {
        case ToolPrimitive::hold:
        case ToolPrimitive::push_sphere:
        case ToolPrimitive::separate:
          break;
        case ToolPrimitive::stitch:
          throw InputError(sfile, t.label, "sutures run on the cpu backend only; set backend: cpu");
        case ToolPrimitive::load:
          throw InputError(sfile, t.label, "force tools run on the cpu backend only; set backend: cpu");
        case ToolPrimitive::push_shape:
          throw InputError(sfile, t.label, "instruments run on the cpu backend only for spring models (the contact kernel is "
                                           "written for CUDA, its device launch is not yet); set backend: cpu");
        case ToolPrimitive::remove:
          throw InputError(sfile, t.label, std::string(t.kind()) + " runs on the cpu backend only for spring models; set backend: cpu");
      }
    }
  }
  EngineOptions o = engine_options(s, note);
  o.dt = s.dt_s;
  if (backend == Backend::cuda && !held.components.empty()) {
    throw InputError(sfile, "fixed", "fixing some axes only runs on the cpu backend for spring models; set backend: cpu");
  }
  auto engine = std::make_unique<SpringEngine>(std::move(model), std::move(state), std::move(surface), origin, o, backend);
  engine->hold_components(held.components);
  const double critical = engine->counts().critical_dt_s;
  if (note) {
    if (s.dt_s > 0 && s.dt_s > critical) {
      note("warning: dt_s " + std::to_string(s.dt_s) + " s is above the critical step " + std::to_string(critical) +
           " s; expect the stability guard to stop the run");
    } else if (s.dt_s == 0) {
      note("auto step " + std::to_string(engine->dt()) + " s (" + std::to_string(s.safety_factor) + " x critical " +
           std::to_string(critical) + " s)");
    }
  }
  r.engine = std::move(engine);
  return r;
}

ScenarioEngine fem_engine(const Scenario& s, Backend backend, const std::function<void(const std::string&)>& note) {
  const std::string sfile = s.file.string();
  TetMesh mesh = read_tet_mesh_file(s.tetmesh);
  // material.labels: every label of the mesh has a material and every material's label is in the mesh.
  const std::vector<int32_t> label_to_material = label_material_index(s, mesh.tet_labels, "the tet mesh", s.tetmesh.string());
  std::vector<FemMaterial> materials;
  for (const LabelMaterial& lm : s.label_materials) materials.push_back(fem_material_of(lm));
  const RestBounds lps_bounds = bounds_of(mesh.nodes);
  const Vec3 origin = local_origin({0.5 * (lps_bounds.lo[0] + lps_bounds.hi[0]), 0.5 * (lps_bounds.lo[1] + lps_bounds.hi[1]),
                                    0.5 * (lps_bounds.lo[2] + lps_bounds.hi[2])});
  for (size_t i = 0; i < mesh.nodes.size(); ++i) mesh.nodes[i] -= origin[i % 3];
  if (s.contact.enabled && (s.contact.split_labels || !s.contact.split_planes.empty())) {
    // The bodies: faces between labels or across planes separated before anything else reads the mesh
    // (the fixed regions, the surface's embedding and the model all see the bodies apart).
    std::vector<HalfSpace> planes = s.contact.split_planes;
    for (HalfSpace& h : planes)
      for (size_t a = 0; a < 3; ++a) h.point[a] -= origin[a];
    const BodySeparation b = separate_bodies(mesh, s.contact.split_labels, planes, s.contact.gap_mm);
    if (b.nodes_split == 0 && b.tets_removed == 0) {
      throw InputError(sfile, "contact.bodies", "separates nothing: the labels or planes do not cross the mesh");
    }
    if (note) {
      note("contact: bodies apart along " + std::to_string(b.faces) + " faces (" + std::to_string(b.nodes_split) + " nodes split, " +
           std::to_string(b.tets_removed) + " tets taken out by the gap)");
    }
  }
  std::vector<int32_t> element_material;
  if (materials.empty()) {
    materials.push_back(fem_material_of(s));
  } else {
    element_material.reserve(mesh.tet_labels.size());
    for (const uint16_t l : mesh.tet_labels) element_material.push_back(label_to_material[l]);
  }
  // Inclusions: the tets whose centroid lies in the sphere take its material (a later one wins).
  const int32_t first_inclusion = static_cast<int32_t>(materials.size());
  for (const InclusionMaterial& inc : s.inclusions) materials.push_back(fem_material_of(inc));
  apply_inclusions(s, first_inclusion, mesh.tet_labels.size(), [&](size_t e) { return tet_centroid(mesh, e); }, lps_bounds, origin, "element",
                   "the tet mesh", element_material, note);
  FemModel model = s.fem_order == 2 ? build_quadratic_fem_model(mesh.nodes, mesh.tets, materials, element_material)
                                    : build_fem_model(mesh.nodes, mesh.tets, materials, element_material);
  model.frame_origin = {origin[0], origin[1], origin[2]};
  // Fixed regions: the rest positions in float (as the spring models select them), the fractions of
  // the double-precision box. A label holds the edge nodes of a quadratic model between its nodes.
  const std::vector<Real> rest_real(model.nodes.begin(), model.nodes.end());
  const auto with_label = [&](uint16_t label) {
    std::vector<int32_t> ids = nodes_with_label(mesh, label);
    if (model.order != 2) return ids;
    std::vector<uint8_t> in(static_cast<size_t>(model.node_count()), 0);
    for (const int32_t i : ids) in[static_cast<size_t>(i)] = 1;
    for (int32_t e = 0; e < model.tet_count(); ++e) {
      const int32_t* t = &model.tets[10 * static_cast<size_t>(e)];
      for (int k = 0; k < 6; ++k) {
        int a, b;
        fem_quadratic_edge(k, a, b);
        if (in[static_cast<size_t>(t[a])] && in[static_cast<size_t>(t[b])]) in[static_cast<size_t>(t[4 + k])] = 1;
      }
    }
    ids.clear();
    for (int32_t i = 0; i < model.node_count(); ++i)
      if (in[static_cast<size_t>(i)]) ids.push_back(i);
    return ids;
  };
  const Held held = fixed_particles(s, rest_real, bounds_of(model.nodes), origin, with_label);
  FemBoundaryConditions supports;
  supports.fixed_nodes = held.whole;
  supports.fixed_components = held.components;

  ScenarioEngine r;
  EmbeddedSurface surface;
  if (model_inputs(s).surface) {
    LocalSurface local = read_local_surface(s, origin);
    r.surface_lps_vertices = std::move(local.lps_vertices);
    surface = embed_in_tets(local.mesh, mesh, note);
  }
  FemEngineOptions o;
  static_cast<EngineOptions&>(o) = engine_options(s, note);
  o.solver = s.fem_solver;
  o.stiffness_damping = s.stiffness_damping_s;
  o.implicit_scheme = s.implicit_scheme;
  o.newton.linear_solve = s.solver.linear;
  o.newton.tolerance_mm = s.solver.tolerance_mm;
  o.newton.max_newton_iterations = s.solver.max_newton_iterations;
  o.newton.nonlinear = s.solver.nonlinear;
  o.newton.cg_max_iterations = s.solver.max_cg_iterations;
  if (s.solver.local_region_mm > 0) o.local_region_mm = s.solver.local_region_mm;
  o.local_region_balance_iterations = s.solver.local_region_balance;
  o.contact.enabled = s.contact.enabled;
  o.contact.self = s.contact.self;
  o.contact.distance_mm = s.contact.distance_mm;
  if (s.fem_solver == FemSolver::implicit) o.dt = s.dt_s;  // 0: a frame's 1/60 s
  std::optional<FemCriticalStep> crit;
  if (s.fem_solver == FemSolver::dynamic) {
    crit = fem_critical_time_step(model, s.safety_factor);
    o.dt = s.dt_s > 0 ? s.dt_s : crit->dt;
    if (o.dt > crit->critical) {
      throw InputError(sfile, "time.dt_s", "the step " + std::to_string(o.dt) + " s is above the FEM critical step " +
                                              std::to_string(crit->critical) + " s (element " + std::to_string(crit->element) +
                                              ", " + std::to_string(crit->length) + " mm); use auto or a smaller step");
    }
  }
  auto engine = std::make_unique<FemEngine>(std::move(model), std::move(supports), std::move(surface), origin, o, backend);
  if (crit && note) {
    note("FEM " + std::string(fem_law_name(s.material_law)) + " explicit dynamics, dt " + std::to_string(engine->dt()) +
         " s (critical " + std::to_string(crit->critical) + " s, element " + std::to_string(crit->element) + ")");
  }
  r.engine = std::move(engine);
  return r;
}

// kind: vessel: the centerline's chain in the frame of its points' centre, the fixed regions over its
// atoms, the surface drawn from the atoms (its rest vertices are the trajectory's rest surface).
ScenarioEngine vessel_engine(const Scenario& s, Backend backend, const std::function<void(const std::string&)>& note) {
  const Centerline centerline = read_centerline_file(s.centerline);
  const RestBounds lps_bounds = bounds_of(centerline.points);
  const Vec3 origin = local_origin({0.5 * (lps_bounds.lo[0] + lps_bounds.hi[0]), 0.5 * (lps_bounds.lo[1] + lps_bounds.hi[1]),
                                    0.5 * (lps_bounds.lo[2] + lps_bounds.hi[2])});
  VesselWall wall;
  wall.youngs_modulus_pa = s.material.youngs_modulus_pa;
  wall.poisson_ratio = s.material.poisson_ratio;
  wall.density = s.material.density;
  wall.thickness_mm = s.vessel.wall_thickness_mm;
  wall.blood_filled = s.vessel.blood_filled;
  VesselChain chain = build_vessel_chain(centerline, origin, wall, s.file.string());
  const std::vector<Real> rest_real(chain.rest.begin(), chain.rest.end());
  const Held held = fixed_particles(s, rest_real, bounds_of(chain.rest), origin, [&](uint16_t) -> std::vector<int32_t> {
    throw InputError(s.file.string(), "fixed", "a centerline has no labels");
  });
  VesselEngineOptions o;
  static_cast<EngineOptions&>(o) = engine_options(s, note);
  o.dt = s.dt_s;  // 0: a frame, 1/60 s
  o.spokes = s.vessel.spokes;
  o.skinning = s.vessel.skinning;
  o.max_newton_iterations = s.vessel.newton_iterations;
  auto engine = std::make_unique<VesselEngine>(std::move(chain), held.whole, origin, o, backend);
  if (note) {
    note("vessel: " + std::to_string(engine->chain().atom_count()) + " atoms, " + std::to_string(engine->chain().segment_count()) +
         " segments, " + std::to_string(engine->chain().branch_count()) + " branches; backward Euler, dt " + std::to_string(engine->dt()) + " s");
  }
  ScenarioEngine r;
  const std::vector<Real>& rest = engine->surface_rest_vertices();
  r.surface_lps_vertices.resize(rest.size());
  for (size_t i = 0; i < rest.size(); ++i) r.surface_lps_vertices[i] = static_cast<float>(static_cast<double>(rest[i]) + origin[i % 3]);
  r.engine = std::move(engine);
  return r;
}

}  // namespace

ScenarioEngine make_scenario_engine(const Scenario& s, const std::function<void(const std::string&)>& note) {
  // cuda: InputError unless this build has CUDA and a device is present; auto: cuda exactly then.
  const Backend backend = resolve_backend(s.backend, s.file.string() + ": backend");
  if (s.model == ModelKind::vessel) return vessel_engine(s, backend, note);
  return s.model == ModelKind::fem ? fem_engine(s, backend, note) : spring_engine(s, backend, note);
}

}  // namespace ctsurg::sim
