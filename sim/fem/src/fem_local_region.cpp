#include "ctsurg/sim/fem/fem_local_region.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/elapsed_seconds.h"
#include "ctsurg/sim/fem/fem_forces.h"
#include "mesh_graph.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <queue>
#include <string>
#include <utility>

namespace ctsurg::sim {
namespace {

constexpr const char* kLocalRegionWhere = "fem local region";

// The mesh's edges as a CSR adjacency over the corner nodes (each row increasing, no repeats).
void edge_adjacency(const FemModel& model, std::vector<int32_t>& offsets, std::vector<int32_t>& list) {
  const size_t npe = static_cast<size_t>(model.nodes_per_element());
  std::vector<std::pair<int32_t, int32_t>> pairs;
  pairs.reserve(12 * static_cast<size_t>(model.tet_count()));
  for (size_t e = 0; e < model.tets.size(); e += npe)
    for (size_t a = 0; a < 4; ++a)
      for (size_t b = a + 1; b < 4; ++b) {
        pairs.emplace_back(model.tets[e + a], model.tets[e + b]);
        pairs.emplace_back(model.tets[e + b], model.tets[e + a]);
      }
  std::vector<int32_t> all;
  build_csr(model.node_count(), pairs, offsets, all);
  list.clear();
  std::vector<int32_t> compact(offsets.size(), 0);
  for (size_t i = 0; i + 1 < offsets.size(); ++i) {
    compact[i] = static_cast<int32_t>(list.size());
    for (int32_t k = offsets[i]; k < offsets[i + 1]; ++k)
      if (k == offsets[i] || all[static_cast<size_t>(k)] != all[static_cast<size_t>(k) - 1]) list.push_back(all[static_cast<size_t>(k)]);
  }
  compact.back() = static_cast<int32_t>(list.size());
  offsets = std::move(compact);
}

// Dijkstra from all seeds at once over the edge graph at rest lengths, up to limit_mm (dist: #N). With
// `start` (#seeds, mm, >= 0), seed k starts at distance start[k] instead of 0: a seed whose own radius is
// R_k starts at limit - R_k, so "dist <= limit" means "within R_k of seed k" for one pass over all tools.
void geodesic(const FemModel& model, const std::vector<int32_t>& offsets, const std::vector<int32_t>& list,
              const std::vector<int32_t>& seeds, double limit_mm, std::vector<double>& dist, const std::vector<double>* start = nullptr) {
  const int32_t n = model.node_count();
  dist.assign(static_cast<size_t>(n), std::numeric_limits<double>::infinity());
  using Item = std::pair<double, int32_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
  for (size_t k = 0; k < seeds.size(); ++k) {
    const int32_t s = seeds[k];
    if (s < 0 || s >= n) throw InputError(kLocalRegionWhere, "seeds", "node " + std::to_string(s) + " out of range (0.." + std::to_string(n - 1) + ")");
    const double d0 = start ? (*start)[k] : 0.0;
    if (d0 <= limit_mm && dist[static_cast<size_t>(s)] > d0) {
      dist[static_cast<size_t>(s)] = d0;
      queue.emplace(d0, s);
    }
  }
  const double* x = model.nodes.data();
  while (!queue.empty()) {
    const auto [d, i] = queue.top();
    queue.pop();
    if (d > dist[static_cast<size_t>(i)]) continue;  // a stale entry
    for (int32_t k = offsets[static_cast<size_t>(i)]; k < offsets[static_cast<size_t>(i) + 1]; ++k) {
      const int32_t j = list[static_cast<size_t>(k)];
      const double* p = x + 3 * static_cast<size_t>(i);
      const double* q = x + 3 * static_cast<size_t>(j);
      const double dj = d + std::sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
      if (dj <= limit_mm && dj < dist[static_cast<size_t>(j)]) {
        dist[static_cast<size_t>(j)] = dj;
        queue.emplace(dj, j);
      }
    }
  }
}

// The model of `tets` (ids into model's tets) alone, its nodes numbered compactly in increasing global
// id (to_global: #n; to_local: #N, -1 elsewhere; must come in all -1 and is left so for the others).
FemModel sub_model(const FemModel& model, const std::vector<int32_t>& tets, std::vector<int32_t>& to_global, std::vector<int32_t>& to_local) {
  to_global.clear();
  for (const int32_t e : tets)
    for (size_t a = 0; a < 4; ++a) to_global.push_back(model.tets[4 * static_cast<size_t>(e) + a]);
  std::sort(to_global.begin(), to_global.end());
  to_global.erase(std::unique(to_global.begin(), to_global.end()), to_global.end());
  std::vector<double> nodes(3 * to_global.size());
  for (size_t l = 0; l < to_global.size(); ++l) {
    to_local[static_cast<size_t>(to_global[l])] = static_cast<int32_t>(l);
    for (size_t c = 0; c < 3; ++c) nodes[3 * l + c] = model.nodes[3 * static_cast<size_t>(to_global[l]) + c];
  }
  std::vector<int32_t> corners(4 * tets.size());
  for (size_t k = 0; k < tets.size(); ++k)
    for (size_t a = 0; a < 4; ++a) corners[4 * k + a] = to_local[static_cast<size_t>(model.tets[4 * static_cast<size_t>(tets[k]) + a])];
  std::vector<int32_t> element_material;  // the tets keep their materials
  if (!model.element_material.empty())
    for (const int32_t e : tets) element_material.push_back(model.element_material[static_cast<size_t>(e)]);
  FemModel m = build_fem_model(nodes, corners, model.materials, element_material);
  m.frame_origin = model.frame_origin;
  return m;
}

}  // namespace

std::vector<double> fem_geodesic_distances(const FemModel& model, const std::vector<int32_t>& seeds, double limit_mm) {
  std::vector<int32_t> offsets, list;
  edge_adjacency(model, offsets, list);
  std::vector<double> dist;
  geodesic(model, offsets, list, seeds, limit_mm, dist);
  return dist;
}

struct FemLocalRegionSolver::Impl {
  const FemModel& model;
  FemLocalRegionOptions options;
  Backend backend;
  FemModel linear_model;  // the same mesh and moduli, the linear law: the global model
  std::unique_ptr<FemLinearStaticSolver> global;
  std::vector<uint8_t> whole;      // #N: a support holds the node
  std::vector<uint8_t> component;  // #N x 3: a support holds this component
  std::vector<int32_t> adj_offsets, adj_list;
  // The region of the last solve.
  std::vector<int32_t> tets;  // its tets, increasing
  std::unique_ptr<FemModel> sub;
  std::unique_ptr<FemStaticSolver> newton;
  std::unique_ptr<FemModel> sub_linear;  // the region's tets with the linear law (the balance's correction)
  std::vector<int32_t> sub_to_global, global_to_sub;  // global_to_sub: #N, -1 outside
  std::vector<int32_t> interface;                     // global ids, increasing
  // The tets at the interface nodes, for its residual: those of the region (its law) and those outside
  // (the linear law, as the global model carries them).
  FemModel ring_in, ring_out;
  std::vector<int32_t> ring_in_to_global, ring_to_global, global_to_ring;  // global_to_ring: into ring_out
  std::vector<uint8_t> flags;
  FemLocalRegionReport report;
  // Scratch.
  std::vector<double> dist;
  std::vector<int32_t> grab_of;  // #N: index into the prescribed nodes, -1

  Impl(const FemModel& m, const FemBoundaryConditions& supports, const FemLocalRegionOptions& o, Backend b)
      : model(m), options(o), backend(b), linear_model(fem_linearised(m)) {
    if (!(options.radius_mm > 0) || !std::isfinite(options.radius_mm))
      throw InputError(kLocalRegionWhere, "radius_mm", "must be a positive number of mm (got " + std::to_string(options.radius_mm) + ")");
    if (options.balance_iterations < 0 || options.balance_iterations > 1000)
      throw InputError(kLocalRegionWhere, "balance_iterations", "must be in 0..1000 (got " + std::to_string(options.balance_iterations) + ")");
    if (!(options.balance_tolerance_mm > 0) || !std::isfinite(options.balance_tolerance_mm))
      throw InputError(kLocalRegionWhere, "balance_tolerance_mm", "must be a positive number of mm");
    if (model.order != 1) throw InputError(kLocalRegionWhere, "order", "the local region runs on linear (4-node) tets only");
    if (!supports.prescribed_nodes.empty()) throw InputError(kLocalRegionWhere, "prescribed_nodes", "supports hold nodes at zero; grabs come with each solve");
    global = std::make_unique<FemLinearStaticSolver>(linear_model, supports, options.linear);
    const size_t n = static_cast<size_t>(model.node_count());
    whole.assign(n, 0);
    component.assign(3 * n, 0);
    for (const int32_t i : supports.fixed_nodes) whole[static_cast<size_t>(i)] = 1;  // ids checked by the global solver
    for (const int32_t c : supports.fixed_components) component[static_cast<size_t>(c)] = 1;
    edge_adjacency(model, adj_offsets, adj_list);
    global_to_sub.assign(n, -1);
    global_to_ring.assign(n, -1);
    grab_of.assign(n, -1);
    flags.assign(n, kFemOutsideRegion);
    options.newton.initial_displacements.clear();
  }

  // Step 2: the region's tets from the seeds' distances; `interface` and `flags` for them.
  // seed_radii (optional, #seeds mm): each seed's own radius instead of options.radius_mm.
  std::vector<int32_t> select(const std::vector<int32_t>& seeds, const std::vector<int32_t>& prescribed,
                              const std::vector<double>* seed_radii) {
    const int32_t n = model.node_count();
    double limit = options.radius_mm;
    std::vector<double> start;
    if (seed_radii) {
      if (seed_radii->size() != seeds.size()) {
        throw InputError(kLocalRegionWhere, "seed_radii", std::to_string(seed_radii->size()) + " radii for " + std::to_string(seeds.size()) + " seeds");
      }
      for (const double r : *seed_radii) {
        if (!(r > 0) || !std::isfinite(r)) throw InputError(kLocalRegionWhere, "seed_radii", "must be positive numbers of mm (got " + std::to_string(r) + ")");
        limit = std::max(limit, r);
      }
      start.resize(seeds.size());
      for (size_t k = 0; k < seeds.size(); ++k) start[k] = limit - (*seed_radii)[k];
    }
    geodesic(model, adj_offsets, adj_list, seeds, limit, dist, seed_radii ? &start : nullptr);
    std::vector<uint8_t> in_tet(static_cast<size_t>(model.tet_count()), 0);
    std::vector<int32_t> chosen;
    for (int32_t e = 0; e < model.tet_count(); ++e) {
      bool all = true;
      for (size_t a = 0; a < 4 && all; ++a) all = dist[static_cast<size_t>(model.tets[4 * static_cast<size_t>(e) + a])] <= limit;
      if (all) {
        in_tet[static_cast<size_t>(e)] = 1;
        chosen.push_back(e);
      }
    }
    if (chosen.empty()) return chosen;
    // Per node of the chosen tets: on the interface (a tet outside; held, whatever else holds it), held
    // (support or tool) or free. The interface depends on the tets alone, not on the tools.
    std::vector<uint8_t> state(static_cast<size_t>(n), 0);  // 0 not in, 1 free, 2 held, 3 interface
    std::vector<uint8_t> tool(static_cast<size_t>(n), 0);
    for (const int32_t p : prescribed) tool[static_cast<size_t>(p)] = 1;
    UnionFind pieces(static_cast<size_t>(n));
    for (const int32_t e : chosen) {
      const int32_t* t = &model.tets[4 * static_cast<size_t>(e)];
      for (size_t a = 1; a < 4; ++a) pieces.unite(t[0], t[a]);
      for (size_t a = 0; a < 4; ++a) {
        const size_t i = static_cast<size_t>(t[a]);
        if (state[i]) continue;
        bool outside = false;
        for (int32_t k = model.node_offsets[i]; k < model.node_offsets[i + 1] && !outside; ++k)
          outside = !in_tet[static_cast<size_t>(model.node_corners[static_cast<size_t>(k)] / 4)];
        state[i] = outside ? 3 : whole[i] || tool[i] ? 2 : 1;
      }
    }
    // Pieces with no free node (nothing to solve) or under 3 held nodes (free to turn about them) go.
    std::vector<int32_t> free_count(static_cast<size_t>(n), 0), held_count(static_cast<size_t>(n), 0);
    for (int32_t i = 0; i < n; ++i) {
      if (!state[static_cast<size_t>(i)]) continue;
      const size_t root = static_cast<size_t>(pieces.find(i));
      (state[static_cast<size_t>(i)] == 1 ? free_count : held_count)[root]++;
    }
    std::vector<int32_t> kept;
    for (const int32_t e : chosen) {
      const size_t root = static_cast<size_t>(pieces.find(model.tets[4 * static_cast<size_t>(e)]));
      if (free_count[root] > 0 && held_count[root] >= 3) kept.push_back(e);
    }
    std::fill(flags.begin(), flags.end(), kFemOutsideRegion);
    interface.clear();
    for (const int32_t e : kept)
      for (size_t a = 0; a < 4; ++a) {
        const size_t i = static_cast<size_t>(model.tets[4 * static_cast<size_t>(e) + a]);
        if (flags[i] != kFemOutsideRegion) continue;
        flags[i] = state[i] == 3 ? kFemRegionInterface : kFemInRegion;
        if (state[i] == 3) interface.push_back(static_cast<int32_t>(i));
      }
    std::sort(interface.begin(), interface.end());
    return kept;
  }

  // The region's model and Newton solver for `kept`, and the ring of tets at its interface.
  void rebuild(std::vector<int32_t> kept) {
    newton.reset();
    for (const int32_t g : sub_to_global) global_to_sub[static_cast<size_t>(g)] = -1;
    for (const int32_t g : ring_to_global) global_to_ring[static_cast<size_t>(g)] = -1;
    sub_to_global.clear();
    ring_to_global.clear();
    ring_in_to_global.clear();
    tets = std::move(kept);
    sub.reset();
    sub_linear.reset();
    if (tets.empty()) return;
    sub = std::make_unique<FemModel>(sub_model(model, tets, sub_to_global, global_to_sub));
    newton = std::make_unique<FemStaticSolver>(*sub, options.newton, backend);
    sub_linear = std::make_unique<FemModel>(fem_linearised(*sub));
    std::vector<int32_t> ring_tets;
    for (const int32_t i : interface)
      for (int32_t k = model.node_offsets[static_cast<size_t>(i)]; k < model.node_offsets[static_cast<size_t>(i) + 1]; ++k)
        ring_tets.push_back(model.node_corners[static_cast<size_t>(k)] / 4);
    std::sort(ring_tets.begin(), ring_tets.end());
    ring_tets.erase(std::unique(ring_tets.begin(), ring_tets.end()), ring_tets.end());
    std::vector<int32_t> inside, outside;
    for (const int32_t e : ring_tets) (std::binary_search(tets.begin(), tets.end(), e) ? inside : outside).push_back(e);
    if (!inside.empty() && !outside.empty()) {
      ring_in = sub_model(model, inside, ring_in_to_global, global_to_ring);
      for (const int32_t g : ring_in_to_global) global_to_ring[static_cast<size_t>(g)] = -1;
      ring_out = sub_model(model, outside, ring_to_global, global_to_ring);
      ring_out = fem_linearised(std::move(ring_out));
    }
  }

  // The composed field's out-of-balance force at the interface nodes (not held): the region's tets by
  // its law, the outside ones linear (the two models the field comes from). 2-norm, uN.
  double interface_residual(const std::vector<double>& u, const FemLoads& loads) {
    if (interface.empty() || ring_to_global.empty()) return 0;
    const auto forces = [&](const FemModel& ring, const std::vector<int32_t>& to_global) {
      std::vector<double> ur(3 * to_global.size()), f;
      for (size_t l = 0; l < to_global.size(); ++l)
        for (size_t c = 0; c < 3; ++c) ur[3 * l + c] = u[3 * static_cast<size_t>(to_global[l]) + c];
      fem_internal_forces(ring, ur, f, options.newton.threads);
      return f;
    };
    std::vector<double> f = forces(ring_out, ring_to_global);
    const std::vector<double> f_in = forces(ring_in, ring_in_to_global);
    for (size_t l = 0; l < ring_in_to_global.size(); ++l) {
      const int32_t o = global_to_ring[static_cast<size_t>(ring_in_to_global[l])];
      if (o >= 0)
        for (size_t c = 0; c < 3; ++c) f[3 * static_cast<size_t>(o) + c] += f_in[3 * l + c];
    }
    double sum = 0;
    for (const int32_t g : interface) {
      const size_t i = static_cast<size_t>(g);
      if (whole[i] || grab_of[i] >= 0) continue;
      const size_t l = static_cast<size_t>(global_to_ring[i]);
      for (size_t c = 0; c < 3; ++c) {
        if (component[3 * i + c]) continue;
        const double r = f[3 * l + c] + (loads.forces.empty() ? 0.0 : loads.forces[3 * i + c]) + model.node_load[i] * loads.gravity[c];
        sum += r * r;
      }
    }
    return std::sqrt(sum);
  }
};

FemLocalRegionSolver::FemLocalRegionSolver(const FemModel& model, const FemBoundaryConditions& supports,
                                           const FemLocalRegionOptions& options, Backend backend)
    : impl_(std::make_unique<Impl>(model, supports, options, backend)) {}

FemLocalRegionSolver::~FemLocalRegionSolver() = default;

const FemLocalRegionReport& FemLocalRegionSolver::report() const { return impl_->report; }
const std::vector<uint8_t>& FemLocalRegionSolver::node_region() const { return impl_->flags; }
const FemLinearSolverStats& FemLocalRegionSolver::linear_stats() const { return impl_->global->stats(); }

FemStaticResult FemLocalRegionSolver::solve(const std::vector<int32_t>& prescribed_nodes, const std::vector<double>& prescribed_displacements,
                                            const FemLoads& loads, const std::vector<int32_t>& seeds, const std::vector<double>* initial,
                                            const std::vector<double>* seed_radii) {
  Impl& s = *impl_;
  const auto t0 = std::chrono::steady_clock::now();
  const size_t n = static_cast<size_t>(s.model.node_count());
  if (initial && initial->size() != 3 * n) {
    throw InputError(kLocalRegionWhere, "initial_displacements", "expected #N x 3 = " + std::to_string(3 * n) + " values, got " + std::to_string(initial->size()));
  }
  // 1. The global linear solve (it checks the arguments).
  FemStaticResult result = s.global->solve(prescribed_nodes, prescribed_displacements, loads);
  FemLocalRegionReport report;
  report.global_seconds = seconds_since(t0);
  const auto t1 = std::chrono::steady_clock::now();
  const bool global_converged = result.report.converged;
  std::fill(s.grab_of.begin(), s.grab_of.end(), -1);
  for (size_t g = 0; g < prescribed_nodes.size(); ++g) s.grab_of[static_cast<size_t>(prescribed_nodes[g])] = static_cast<int32_t>(g);

  // 2. The region, its model and solver rebuilt when its tets changed.
  std::vector<int32_t> kept = s.select(seeds, prescribed_nodes, seed_radii);
  if (kept != s.tets) {
    s.rebuild(std::move(kept));
    report.rebuilt = true;
  }

  // 3. The nonlinear solve on the region, the interface held at the global solution.
  FemStaticReport newton_report;
  newton_report.converged = true;
  if (s.sub) {
    const size_t m = s.sub_to_global.size();
    FemBoundaryConditions bc;
    for (size_t l = 0; l < m; ++l) {
      const size_t g = static_cast<size_t>(s.sub_to_global[l]);
      const int32_t li = static_cast<int32_t>(l);
      if (s.whole[g]) {
        bc.fixed_nodes.push_back(li);
      } else if (s.grab_of[g] >= 0) {
        bc.prescribed_nodes.push_back(li);
        for (size_t c = 0; c < 3; ++c) bc.prescribed_displacements.push_back(prescribed_displacements[3 * static_cast<size_t>(s.grab_of[g]) + c]);
      } else if (s.flags[g] == kFemRegionInterface) {
        bc.prescribed_nodes.push_back(li);
        for (size_t c = 0; c < 3; ++c) bc.prescribed_displacements.push_back(result.displacements[3 * g + c]);
      } else {
        for (int32_t c = 0; c < 3; ++c)
          if (s.component[3 * g + static_cast<size_t>(c)]) bc.fixed_components.push_back(3 * li + c);
      }
    }
    FemLoads sub_loads;
    sub_loads.gravity = loads.gravity;
    if (!loads.forces.empty()) {
      sub_loads.forces.resize(3 * m);
      for (size_t l = 0; l < m; ++l)
        for (size_t c = 0; c < 3; ++c) sub_loads.forces[3 * l + c] = loads.forces[3 * static_cast<size_t>(s.sub_to_global[l]) + c];
    }
    std::vector<double> start;
    if (initial) {
      start.resize(3 * m);
      for (size_t l = 0; l < m; ++l)
        for (size_t c = 0; c < 3; ++c) start[3 * l + c] = (*initial)[3 * static_cast<size_t>(s.sub_to_global[l]) + c];
    }
    // The interface's slots in bc.prescribed_displacements (local node, slot).
    std::vector<std::pair<size_t, size_t>> slots;
    for (size_t k = 0; k < bc.prescribed_nodes.size(); ++k) {
      const size_t g = static_cast<size_t>(s.sub_to_global[static_cast<size_t>(bc.prescribed_nodes[k])]);
      if (s.grab_of[g] < 0) slots.emplace_back(static_cast<size_t>(bc.prescribed_nodes[k]), 3 * k);
    }
    int newton_iterations = 0;
    std::vector<int> cg_iterations;
    bool converged = true;
    for (int k = 0;; ++k) {
      FemStaticResult r = s.newton->solve(bc, sub_loads, k > 0 || initial ? &start : nullptr);
      newton_iterations += r.report.newton_iterations;
      cg_iterations.insert(cg_iterations.end(), r.report.cg_iterations.begin(), r.report.cg_iterations.end());
      converged = converged && r.report.converged;
      // 4. Compose: the region's nodes from the nonlinear solve.
      for (size_t l = 0; l < m; ++l) {
        const size_t g = static_cast<size_t>(s.sub_to_global[l]);
        for (size_t c = 0; c < 3; ++c) result.displacements[3 * g + c] = r.displacements[3 * l + c];
        if (s.whole[g] || s.grab_of[g] >= 0)
          for (size_t c = 0; c < 3; ++c) result.reactions[3 * g + c] = r.reactions[3 * l + c];
      }
      newton_report = std::move(r.report);
      start = std::move(r.displacements);
      if (k >= s.options.balance_iterations || slots.empty()) break;
      // Balance: the global linear solve again, with the region's tets' nonlinear forces in place of
      // their linear ones (f_ext + f_law - f_linear over the region's nodes). At its fixed point the
      // global solution is in equilibrium at the interface with the region's law inside and the linear
      // law outside, and the region's interior is the region's solve.
      std::vector<double> f_law, f_linear;
      fem_internal_forces(*s.sub, start, f_law, s.options.newton.threads);
      fem_internal_forces(*s.sub_linear, start, f_linear, s.options.newton.threads);
      FemLoads balanced = loads;
      if (balanced.forces.empty()) balanced.forces.assign(3 * n, 0.0);
      for (size_t l = 0; l < m; ++l) {
        const size_t g = static_cast<size_t>(s.sub_to_global[l]);
        if (s.whole[g] || s.grab_of[g] >= 0) continue;  // held: the correction would only change a reaction
        for (size_t c = 0; c < 3; ++c)
          if (!s.component[3 * g + c]) balanced.forces[3 * g + c] += f_law[3 * l + c] - f_linear[3 * l + c];
      }
      FemStaticResult g = s.global->solve(prescribed_nodes, prescribed_displacements, balanced);
      converged = converged && g.report.converged;
      ++report.balance_iterations;
      double change = 0;
      for (const auto& [l, slot] : slots)
        for (size_t c = 0; c < 3; ++c) {
          const double v = g.displacements[3 * static_cast<size_t>(s.sub_to_global[l]) + c];
          change = std::max(change, std::abs(v - bc.prescribed_displacements[slot + c]));
          bc.prescribed_displacements[slot + c] = v;
        }
      // The outside from the balanced global solve; the region as solved (within `change` of it).
      for (size_t i = 0; i < n; ++i) {
        if (s.global_to_sub[i] >= 0) continue;
        for (size_t c = 0; c < 3; ++c) {
          result.displacements[3 * i + c] = g.displacements[3 * i + c];
          result.reactions[3 * i + c] = g.reactions[3 * i + c];
        }
      }
      report.balance_change_mm = change;
      if (change <= s.options.balance_tolerance_mm) break;
    }
    newton_report.newton_iterations = newton_iterations;
    newton_report.cg_iterations = std::move(cg_iterations);
    newton_report.converged = converged;
    report.region_nodes = static_cast<int32_t>(m);
    report.region_tets = static_cast<int32_t>(s.tets.size());
    report.interface_nodes = static_cast<int32_t>(s.interface.size());
  }
  report.interface_residual = s.interface_residual(result.displacements, loads);
  double load[3] = {0, 0, 0};
  for (const int32_t p : prescribed_nodes)
    for (size_t c = 0; c < 3; ++c) load[c] += result.reactions[3 * static_cast<size_t>(p) + c];
  if (!loads.forces.empty())
    for (size_t i = 0; i < n; ++i)
      for (size_t c = 0; c < 3; ++c) load[c] += loads.forces[3 * i + c];
  report.tool_load = std::sqrt(load[0] * load[0] + load[1] * load[1] + load[2] * load[2]);
  report.region_seconds = seconds_since(t1);

  const double global_seconds = report.global_seconds;
  newton_report.converged = newton_report.converged && global_converged;
  newton_report.seconds = global_seconds + report.region_seconds;
  result.report = std::move(newton_report);
  s.report = report;
  return result;
}

}  // namespace ctsurg::sim
