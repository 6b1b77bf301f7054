// Collision detection (sim/collision) timings: the spatial hash (Teschner et al. 2003), rebuilt and queried
// every step, against CGAL's AABB tree (CGAL 5.5, Simple_cartesian<double>; the tree rebuilt every step too,
// as a deforming mesh needs) and against brute force, on the same queries.
//
// Scene: two wavy sheets of triangles (objects 0 and 1, edge 1 mm, z about 650 mm) that cross each other,
// #F triangles in all (10k .. 1M; brute force up to 10k); query: every vertex against every triangle of
// the other object within 0.2 mm (vertex_triangle_contacts). Counters: primitives, vertices, contacts,
// ns_per_primitive (time / #F: flat when the time is linear in #F). CGAL's answer: for each vertex, the
// triangles whose boxes meet the cube [p - d, p + d] (all_intersected_primitives with an Iso_cuboid_3),
// then the same exact test (kernels/contact_tests_impl.h); one thread (CGAL's tree queries are serial),
// so the hash is timed with 1 thread and with the library's default (threads counter 0: one thread per
// 8,192 items, up to every core; sim/base/parallel.h). And the vertex-in-tet query on a box of Kuhn tets with as
// many random points as nodes (10k .. 1M tets).
#include "ctsurg/sim/collision/spatial_hash.h"
#include "ctsurg/sim/collision/vertex_tet_contacts.h"
#include "ctsurg/sim/collision/vertex_triangle_contacts.h"
#include "ctsurg/sim/fem/fem_box_mesh.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <map>
#include <random>
#include <vector>

namespace {

using namespace ctsurg::sim;

constexpr double kDistance = 0.2;  // mm

struct Sheets {
  std::vector<double> positions;
  std::vector<uint32_t> triangles, vertex_object, triangle_object;
};

// Two n x n sheets of 1 mm squares (2 triangles each): z = 650 + 0.5 sin(x / 5) and z = 650 + 0.5 cos(y / 4),
// which cross along curves, so a few percent of the vertices have contacts.
const Sheets& sheets(int64_t triangles) {
  static std::map<int64_t, Sheets> cache;
  auto [it, fresh] = cache.try_emplace(triangles);
  if (!fresh) return it->second;
  Sheets& s = it->second;
  const int n = static_cast<int>(std::lround(std::sqrt(triangles / 4.0)));
  for (uint32_t object = 0; object < 2; ++object) {
    const uint32_t base = static_cast<uint32_t>(s.vertex_object.size());
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        const double x = i, y = j;
        const double z = 650 + (object == 0 ? 0.5 * std::sin(x / 5) : 0.5 * std::cos(y / 4));
        s.positions.insert(s.positions.end(), {x + 0.5 * object, y + 0.5 * object, z});
        s.vertex_object.push_back(object);
      }
    const auto id = [n, base](int i, int j) { return base + static_cast<uint32_t>(i + (n + 1) * j); };
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        s.triangles.insert(s.triangles.end(), {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j), id(i + 1, j + 1),
                                               id(i, j + 1)});
        s.triangle_object.insert(s.triangle_object.end(), {object, object});
      }
  }
  return s;
}

void counters(benchmark::State& state, const Sheets& s, int64_t contacts) {
  const double f = static_cast<double>(s.triangle_object.size());
  state.counters["primitives"] = f;
  state.counters["vertices"] = static_cast<double>(s.vertex_object.size());
  state.counters["contacts"] = static_cast<double>(contacts);
  state.counters["ns_per_primitive"] =
      benchmark::Counter(f * 1e-9, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

// Build + query, every step from scratch.
void HashContacts(benchmark::State& state) {
  const Sheets& s = sheets(state.range(0));
  ContactOptions o;
  o.threads = static_cast<int>(state.range(1));
  int64_t contacts = 0;
  for (auto _ : state) {
    const auto c = vertex_triangle_contacts(s.positions, s.triangles, s.vertex_object, s.triangle_object, kDistance, o);
    contacts = static_cast<int64_t>(c.size());
    benchmark::DoNotOptimize(c.data());
  }
  counters(state, s, contacts);
  state.counters["omp_threads"] = static_cast<double>(o.threads);
}

// The table alone (the build's share of a step).
void HashBuild(benchmark::State& state) {
  const Sheets& s = sheets(state.range(0));
  int64_t entries = 0;
  for (auto _ : state) {
    const SpatialHash h = build_spatial_hash(s.positions, s.triangles, 3, kDistance, 0, static_cast<int>(state.range(1)));
    entries = static_cast<int64_t>(h.entries.size());
    benchmark::DoNotOptimize(h.entries.data());
  }
  counters(state, s, 0);
  state.counters["entries_per_primitive"] = static_cast<double>(entries) / static_cast<double>(s.triangle_object.size());
  state.counters["omp_threads"] = static_cast<double>(state.range(1));
}

// CGAL's AABB tree: rebuilt, queried with each vertex's cube, candidates checked by the same exact test.
using Kernel = CGAL::Simple_cartesian<double>;
using Triangle = Kernel::Triangle_3;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, std::vector<Triangle>::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

int64_t cgal_contacts(const Sheets& s) {
  const auto& x = s.positions;
  std::vector<Triangle> triangles;
  triangles.reserve(s.triangle_object.size());
  for (std::size_t t = 0; t < s.triangle_object.size(); ++t) {
    const uint32_t* f = s.triangles.data() + 3 * t;
    triangles.emplace_back(Kernel::Point_3(x[3 * f[0]], x[3 * f[0] + 1], x[3 * f[0] + 2]),
                           Kernel::Point_3(x[3 * f[1]], x[3 * f[1] + 1], x[3 * f[1] + 2]),
                           Kernel::Point_3(x[3 * f[2]], x[3 * f[2] + 1], x[3 * f[2] + 2]));
  }
  Tree tree(triangles.begin(), triangles.end());
  tree.build();
  const VertexTriangleTest test{
      {x.data(), s.triangles.data(), static_cast<int64_t>(s.triangle_object.size()), 3, kDistance * (1 + 1e-9), 0},
      {s.vertex_object.data(), s.triangle_object.data(), false},
      kDistance};
  int64_t contacts = 0;
  std::vector<Tree::Primitive_id> hits;
  std::vector<uint32_t> ids;
  for (uint32_t v = 0; v < s.vertex_object.size(); ++v) {
    const double* p = x.data() + 3 * v;
    const Kernel::Iso_cuboid_3 cube(p[0] - kDistance, p[1] - kDistance, p[2] - kDistance, p[0] + kDistance,
                                    p[1] + kDistance, p[2] + kDistance);
    hits.clear();
    tree.all_intersected_primitives(cube, std::back_inserter(hits));
    ids.clear();
    for (const auto& h : hits) ids.push_back(static_cast<uint32_t>(h - triangles.cbegin()));
    std::sort(ids.begin(), ids.end());  // the records in (vertex, triangle) order, as the hash gives them
    for (const uint32_t t : ids) {
      VertexTriangleContact c{};
      contacts += test(v, t, c);
    }
  }
  return contacts;
}

void CgalAabbTreeContacts(benchmark::State& state) {
  const Sheets& s = sheets(state.range(0));
  int64_t contacts = 0;
  for (auto _ : state) {
    contacts = cgal_contacts(s);
    benchmark::DoNotOptimize(contacts);
  }
  const auto hashed = vertex_triangle_contacts(s.positions, s.triangles, s.vertex_object, s.triangle_object, kDistance);
  if (static_cast<int64_t>(hashed.size()) != contacts) state.SkipWithError("CGAL and the hash disagree");
  counters(state, s, contacts);
  state.counters["omp_threads"] = 1;
}

void BruteForceContacts(benchmark::State& state) {
  const Sheets& s = sheets(state.range(0));
  int64_t contacts = 0;
  for (auto _ : state) {
    const auto c = vertex_triangle_contacts_brute_force(s.positions, s.triangles, s.vertex_object, s.triangle_object,
                                                        kDistance, ContactPairs::between_objects);
    contacts = static_cast<int64_t>(c.size());
    benchmark::DoNotOptimize(c.data());
  }
  counters(state, s, contacts);
  state.counters["omp_threads"] = 1;
}

// Vertices in tets: a box of Kuhn tets (1 mm cells at z = 650) and as many random points as nodes.
struct TetScene {
  std::vector<double> positions;
  std::vector<uint32_t> tets, vertex_object, tet_object;
};

const TetScene& tet_scene(int64_t tets) {
  static std::map<int64_t, TetScene> cache;
  auto [it, fresh] = cache.try_emplace(tets);
  if (!fresh) return it->second;
  TetScene& s = it->second;
  const int n = static_cast<int>(std::lround(std::cbrt(tets / 6.0)));
  const FemBoxMesh box = fem_box_mesh({n, n, n}, {double(n), double(n), double(n)}, {0, 0, 650});
  s.positions = box.nodes;
  s.tets.assign(box.tets.begin(), box.tets.end());
  s.tet_object.assign(s.tets.size() / 4, 0);
  const std::size_t nodes = box.nodes.size() / 3;
  s.vertex_object.assign(nodes, 0);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-0.05, 1.05);
  for (std::size_t p = 0; p < nodes; ++p) {
    s.positions.insert(s.positions.end(), {n * u(rng), n * u(rng), 650 + n * u(rng)});
    s.vertex_object.push_back(1);
  }
  return s;
}

void HashTetContacts(benchmark::State& state) {
  const TetScene& s = tet_scene(state.range(0));
  ContactOptions o;
  o.threads = static_cast<int>(state.range(1));
  int64_t contacts = 0;
  for (auto _ : state) {
    const auto c = vertex_tet_contacts(s.positions, s.tets, s.vertex_object, s.tet_object, o);
    contacts = static_cast<int64_t>(c.size());
    benchmark::DoNotOptimize(c.data());
  }
  const double t = static_cast<double>(s.tet_object.size());
  state.counters["primitives"] = t;
  state.counters["vertices"] = static_cast<double>(s.vertex_object.size());
  state.counters["contacts"] = static_cast<double>(contacts);
  state.counters["ns_per_primitive"] =
      benchmark::Counter(t * 1e-9, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["omp_threads"] = static_cast<double>(o.threads);
}

void sizes(benchmark::internal::Benchmark* b, std::initializer_list<int64_t> triangles,
           std::initializer_list<int64_t> threads) {
  for (const int64_t t : threads)
    for (const int64_t f : triangles) b->Args({f, t});
  b->Unit(benchmark::kMillisecond)->UseRealTime();
}

BENCHMARK(BruteForceContacts)->Apply([](auto* b) { sizes(b, {1000, 3000, 10000}, {1}); });
BENCHMARK(CgalAabbTreeContacts)->Apply([](auto* b) { sizes(b, {1000, 3000, 10000, 30000, 100000, 300000, 1000000}, {1}); });
BENCHMARK(HashContacts)->Apply([](auto* b) {
  sizes(b, {1000, 3000, 10000, 30000, 100000, 300000, 1000000}, {1, 0});
});
BENCHMARK(HashBuild)->Apply([](auto* b) { sizes(b, {10000, 100000, 1000000}, {1, 0}); });
BENCHMARK(HashTetContacts)->Apply([](auto* b) { sizes(b, {10000, 100000, 1000000}, {1, 0}); });

}  // namespace

BENCHMARK_MAIN();
