// Tests for ctsurg/render/gltf_animation.h: trajectories on the synthetic normal-mapped organ exported to
// animated glTF and read back here (JSON, BIN, sparse and empty accessors decoded by hand): one morph
// target per frame after the first, weights one-hot at the keys and at most two non-zero between them,
// positions and normals at each key equal to the trajectory's frame in the glTF frame (metres, +Y up:
// gltf_frame.h) and to the renderer's deformed normals, the normal map and tangents, sparse targets for
// frames that move few vertices; a cut trajectory as one node per topology shown one at a time (scale,
// STEP), the closing triangles as the wound; the Khronos validator without errors or warnings;
// byte-identical reruns; and bad input refused naming the problem.
#include "ctsurg/render/gltf_animation.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <numeric>

#include "ctsurg/core/error.h"
#include "ctsurg/mesh/gltf_frame.h"
#include "ctsurg/mesh/gltf_material.h"
#include "ctsurg/render/deformed_tangent_frames.h"
#include "gltf_animation_scenes.h"
#include "gltf_checks.h"
#include "test_support.h"

namespace ctsurg {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// Writes the files of an export to `dir` and reads the output back.
test::GltfFile export_and_read(const fs::path& dir, const std::string& name, const SurfaceMesh& surface,
                               const Trajectory* trajectory, const GltfAnimationOptions& options = {},
                               GltfAnimationSummary* summary = nullptr) {
  for (const auto& [file, bytes] : export_gltf_animation(dir / name, surface, trajectory, options, summary)) {
    std::ofstream(dir / file, std::ios::binary) << bytes;
  }
  return test::read_gltf(dir / name);
}

// Accessor `index` as count x width floats: zeros where it has no buffer view, then its sparse values.
std::vector<float> decode(const test::GltfFile& g, std::size_t index) {
  const json& a = g.json.at("accessors").at(index);
  const std::size_t width = a.at("type") == "VEC4" ? 4 : a.at("type") == "VEC3" ? 3 : a.at("type") == "VEC2" ? 2 : 1;
  std::vector<float> out(width * a.at("count").get<std::size_t>(), 0.0f);
  if (a.contains("bufferView")) out = g.floats(index);
  if (a.contains("sparse")) {
    const json& s = a.at("sparse");
    const std::size_t m = s.at("count").get<std::size_t>();
    const auto view_offset = [&](const json& part) {
      return g.json.at("bufferViews").at(part.at("bufferView").get<std::size_t>()).value("byteOffset", std::size_t{0}) +
             part.value("byteOffset", std::size_t{0});
    };
    const std::size_t id_size = s.at("indices").at("componentType") == 5125 ? 4 : s.at("indices").at("componentType") == 5123 ? 2 : 1;
    const std::size_t ids = view_offset(s.at("indices")), values = view_offset(s.at("values"));
    EXPECT_LE(values + m * width * 4, g.bin.size());
    uint32_t previous = 0;
    for (std::size_t k = 0; k < m; ++k) {
      uint32_t id = 0;
      std::memcpy(&id, g.bin.data() + ids + k * id_size, id_size);
      EXPECT_TRUE(k == 0 || id > previous) << "sparse indices must increase";
      previous = id;
      std::memcpy(&out.at(id * width), g.bin.data() + values + k * width * 4, width * 4);
    }
  }
  return out;
}

// A sampler's value at time t (glTF 2.0, appendix C): LINEAR or STEP between keys, clamped outside.
std::vector<float> sample(const test::GltfFile& g, const json& sampler, float t) {
  const std::vector<float> keys = decode(g, sampler.at("input").get<std::size_t>());
  const std::vector<float> values = decode(g, sampler.at("output").get<std::size_t>());
  const std::size_t width = values.size() / keys.size();
  std::size_t k = 0;
  while (k + 1 < keys.size() && keys[k + 1] <= t) ++k;
  std::vector<float> out(values.begin() + long(k * width), values.begin() + long((k + 1) * width));
  if (sampler.at("interpolation") == "LINEAR" && k + 1 < keys.size() && t > keys[k]) {
    const float s = (t - keys[k]) / (keys[k + 1] - keys[k]);
    for (std::size_t c = 0; c < width; ++c) out[c] = (1 - s) * out[c] + s * values[(k + 1) * width + c];
  }
  return out;
}

// The sampler driving `path` of node `node` (nullptr when none).
const json* channel_sampler(const test::GltfFile& g, std::size_t node, const std::string& path) {
  const json& animation = g.json.at("animations").at(0);
  for (const json& c : animation.at("channels"))
    if (c.at("target").at("node") == node && c.at("target").at("path") == path) return &animation.at("samplers").at(c.at("sampler").get<std::size_t>());
  return nullptr;
}

// Node `node`'s world positions (#V x 3, metres) with morph weights `w`: translation + base + sum w_j target_j.
std::vector<float> morphed(const test::GltfFile& g, std::size_t node, const std::vector<float>& w, const std::string& attribute = "POSITION") {
  const json& n = g.json.at("nodes").at(node);
  const json& primitive = g.json.at("meshes").at(n.at("mesh").get<std::size_t>()).at("primitives").at(0);
  std::vector<float> p = decode(g, primitive.at("attributes").at(attribute).get<std::size_t>());
  for (std::size_t j = 0; j < w.size(); ++j) {
    if (w[j] == 0.0f) continue;
    const std::vector<float> d = decode(g, primitive.at("targets").at(j).at(attribute).get<std::size_t>());
    for (std::size_t k = 0; k < p.size(); ++k) p[k] += w[j] * d[k];
  }
  if (attribute == "POSITION")
    for (std::size_t k = 0; k < p.size(); ++k) p[k] += n.at("translation").at(k % 3).get<float>();
  return p;
}

// The glTF positions of LPS millimetre vertices.
std::vector<float> gltf_positions(const float* lps, std::size_t count) {
  std::vector<float> out;
  for (std::size_t v = 0; v < count; ++v) {
    const auto q = lps_mm_to_gltf_position(lps + 3 * v);
    out.insert(out.end(), q.begin(), q.end());
  }
  return out;
}

float max_abs_difference(const std::vector<float>& a, const std::vector<float>& b) {
  EXPECT_EQ(a.size(), b.size());
  float m = 0.0f;
  for (std::size_t k = 0; k < std::min(a.size(), b.size()); ++k) m = std::max(m, std::abs(a[k] - b[k]));
  return m;
}

TEST(GltfAnimation, MorphTargetsReplayTheTrajectoryFrameByFrame) {
  test::TempDir dir;
  const SurfaceMesh surface = test::bumpy_organ_surface(24, 12, 64);
  const Trajectory t = test::bump_trajectory(surface);
  const std::size_t nv = surface.vertices.size() / 3, frames = t.time.size();
  GltfAnimationSummary summary;
  const test::GltfFile g = export_and_read(dir.path(), "bump.glb", surface, &t, {}, &summary);
  EXPECT_EQ(summary.frames, 6);
  EXPECT_EQ(summary.morph_targets, 5);
  EXPECT_EQ(summary.nodes, 1);
  EXPECT_EQ(summary.bytes, static_cast<int64_t>(fs::file_size(dir / "bump.glb")));
  EXPECT_TRUE(test::gltf_validates_cleanly({dir / "bump.glb"}));

  // One node and mesh; the base attributes, the map, one target per frame after the first.
  ASSERT_EQ(g.json.at("nodes").size(), 1u);
  ASSERT_EQ(g.json.at("meshes").size(), 1u);
  const json& primitive = g.json.at("meshes").at(0).at("primitives").at(0);
  EXPECT_EQ(g.json.at("accessors").at(primitive.at("attributes").at("POSITION").get<std::size_t>()).at("count"), nv);
  for (const char* a : {"NORMAL", "TANGENT", "TEXCOORD_0"}) EXPECT_TRUE(primitive.at("attributes").contains(a)) << a;
  EXPECT_TRUE(g.json.at("materials").at(primitive.at("material").get<std::size_t>()).contains("normalTexture"));
  // glTF base colours are linear: the on-screen tissue colour decoded from sRGB (0.80 -> 0.604).
  const json& base = g.json.at("materials").at(primitive.at("material").get<std::size_t>()).at("pbrMetallicRoughness").at("baseColorFactor");
  EXPECT_NEAR(base.at(0).get<double>(), 0.6038, 1e-3);
  EXPECT_NEAR(base.at(1).get<double>(), ctsurg::srgb_to_linear(ctsurg::kGltfTissueOnScreen[1]), 1e-12);
  EXPECT_EQ(g.json.at("images").at(0).at("mimeType"), "image/png");
  ASSERT_EQ(primitive.at("targets").size(), frames - 1);
  EXPECT_EQ(g.json.at("meshes").at(0).at("extras").at("targetNames").at(0), "frame 1");
  EXPECT_FALSE(g.json.at("asset").contains("extensionsUsed"));
  EXPECT_FALSE(g.json.contains("extensionsUsed"));
  // The bump moves the front only: some targets are sparse; the last frame is the rest again: no data.
  int sparse = 0, empty = 0;
  for (const json& target : primitive.at("targets")) {
    const json& a = g.json.at("accessors").at(target.at("POSITION").get<std::size_t>());
    sparse += a.contains("sparse");
    empty += !a.contains("sparse") && !a.contains("bufferView");
  }
  EXPECT_GE(sparse, 1);
  EXPECT_EQ(empty, 1);
  const json& last = g.json.at("accessors").at(primitive.at("targets").at(frames - 2).at("NORMAL").get<std::size_t>());
  EXPECT_FALSE(last.contains("bufferView") || last.contains("sparse")) << "the rest frame's normals moved";
  EXPECT_GE(summary.sparse_targets, 3);

  // One channel: weights, LINEAR, keyed at the frames' times.
  const json& animation = g.json.at("animations").at(0);
  ASSERT_EQ(animation.at("channels").size(), 1u);
  const json* weights = channel_sampler(g, 0, "weights");
  ASSERT_NE(weights, nullptr);
  EXPECT_EQ(weights->at("interpolation"), "LINEAR");
  const std::vector<float> keys = decode(g, weights->at("input").get<std::size_t>());
  ASSERT_EQ(keys.size(), frames + 1);
  for (std::size_t i = 0; i < frames; ++i) EXPECT_EQ(keys[i], static_cast<float>(t.time[i])) << i;
  // The last frame is held for one more frame interval (0.6 s + 0.1 s).
  EXPECT_FLOAT_EQ(keys[frames], 0.7f);
  EXPECT_EQ(sample(g, *weights, 0.65f), sample(g, *weights, keys[frames - 1]));

  DeformedTangentFrames tangent_frames(surface);
  for (std::size_t i = 0; i < frames; ++i) {
    // One-hot at key i (all zero at the base).
    const std::vector<float> w = sample(g, *weights, keys[i]);
    ASSERT_EQ(w.size(), frames - 1);
    for (std::size_t j = 0; j < w.size(); ++j) EXPECT_EQ(w[j], i > 0 && j == i - 1 ? 1.0f : 0.0f) << "key " << i << " weight " << j;
    // The frame's positions, to float precision (metres: 1e-7 m = 0.1 um).
    const std::vector<float> expected = gltf_positions(t.frame_vertices(int64_t(i)), nv);
    EXPECT_LT(max_abs_difference(morphed(g, 0, w), expected), 1e-7f) << "frame " << i;
    // And the renderer's deformed normals, rotated into the glTF frame.
    std::vector<float> n, tangents, expected_normals;
    tangent_frames.compute(t.frame_vertices(int64_t(i)), t.topologies[0], 0, n, tangents);
    for (std::size_t v = 0; v < nv; ++v) {
      const auto r = lps_to_gltf_direction(&n[3 * v]);
      expected_normals.insert(expected_normals.end(), r.begin(), r.end());
    }
    EXPECT_LT(max_abs_difference(morphed(g, 0, w, "NORMAL"), expected_normals), 1e-6f) << "frame " << i;
    // Halfway to the next key: at most (here exactly) two weights non-zero, summing to one.
    if (i + 1 < frames) {
      const std::vector<float> mid = sample(g, *weights, 0.5f * (keys[i] + keys[i + 1]));
      EXPECT_EQ(std::count_if(mid.begin(), mid.end(), [](float x) { return x != 0.0f; }), i == 0 ? 1 : 2) << "after key " << i;
      EXPECT_NEAR(std::accumulate(mid.begin(), mid.end(), 0.0f), i == 0 ? 0.5f : 1.0f, 1e-6f);
    }
  }
  // The bump really moved something (frame 2: 5 mm), and frame 0 is the surface itself.
  EXPECT_GT(max_abs_difference(gltf_positions(t.frame_vertices(2), nv), gltf_positions(t.frame_vertices(0), nv)), 4e-3f);
  EXPECT_EQ(gltf_positions(t.frame_vertices(0), nv), gltf_positions(surface.vertices.data(), nv));

  // The same export again: the same bytes; .gltf: the JSON and a .bin it names, equally valid.
  const auto again = export_gltf_animation(dir / "bump.glb", surface, &t);
  EXPECT_TRUE(again.at(0).second == test::read_bytes(dir / "bump.glb"));
  const test::GltfFile text = export_and_read(dir.path(), "bump copy.gltf", surface, &t);
  EXPECT_EQ(text.json.at("buffers").at(0).at("uri"), "bump%20copy.bin");
  EXPECT_TRUE(fs::exists(dir / "bump copy.bin"));
  EXPECT_EQ(gltf_animation_files(dir / "bump copy.gltf"), (std::vector<fs::path>{dir / "bump copy.gltf", dir / "bump copy.bin"}));
  EXPECT_TRUE(test::gltf_validates_cleanly({dir / "bump copy.gltf"}));
  EXPECT_EQ(text.json.at("accessors"), g.json.at("accessors"));
}

TEST(GltfAnimation, TimeScaleFramesAndNoNormalMap) {
  test::TempDir dir;
  const SurfaceMesh surface = test::bumpy_organ_surface(24, 12, 64);
  const Trajectory t = test::bump_trajectory(surface);
  GltfAnimationOptions options;
  options.frames = {1, 2, 4};
  options.time_scale = 10.0;
  options.normal_map = false;
  const test::GltfFile g = export_and_read(dir.path(), "part.glb", surface, &t, options);
  EXPECT_TRUE(test::gltf_validates_cleanly({dir / "part.glb"}));
  // Keys from the first exported frame, ten times slower; two targets (frames 2 and 4 against frame 1).
  const std::vector<float> keys = decode(g, channel_sampler(g, 0, "weights")->at("input").get<std::size_t>());
  ASSERT_EQ(keys.size(), 4u);
  EXPECT_EQ(keys[0], 0.0f);
  EXPECT_FLOAT_EQ(keys[1], 1.5f);
  EXPECT_FLOAT_EQ(keys[2], 4.0f);
  EXPECT_FLOAT_EQ(keys[3], 6.5f);  // the hold
  EXPECT_EQ(g.json.at("animations").at(0).at("extras").at("ctsurg_frames"), json({1, 2, 4}));
  EXPECT_EQ(g.json.at("animations").at(0).at("extras").at("ctsurg_time_scale"), 10.0);
  const json& primitive = g.json.at("meshes").at(0).at("primitives").at(0);
  EXPECT_EQ(primitive.at("targets").size(), 2u);
  const std::size_t nv = surface.vertices.size() / 3;
  EXPECT_LT(max_abs_difference(morphed(g, 0, {}), gltf_positions(t.frame_vertices(1), nv)), 1e-7f);
  EXPECT_LT(max_abs_difference(morphed(g, 0, {0.0f, 1.0f}), gltf_positions(t.frame_vertices(4), nv)), 1e-7f);
  // Without the map: no texture, no tangents or texture coordinates.
  EXPECT_FALSE(g.json.contains("images"));
  EXPECT_FALSE(g.json.at("materials").at(0).contains("normalTexture"));
  EXPECT_FALSE(primitive.at("attributes").contains("TANGENT"));
  EXPECT_FALSE(primitive.at("attributes").contains("TEXCOORD_0"));
}

TEST(GltfAnimation, ACutTrajectoryShowsOneTopologyNodeAtATime) {
  test::TempDir dir;
  const SurfaceMesh surface = test::bumpy_organ_surface(24, 12, 64);
  const Trajectory t = test::cut_trajectory_with_wound(surface);  // topologies 0, 0, 1 at 0, 0.5, 1 s
  const std::size_t nv = surface.vertices.size() / 3;
  GltfAnimationSummary summary;
  const test::GltfFile g = export_and_read(dir.path(), "cut.glb", surface, &t, {}, &summary);
  EXPECT_TRUE(test::gltf_validates_cleanly({dir / "cut.glb"}));
  EXPECT_EQ(summary.morph_targets, 2);
  ASSERT_EQ(g.json.at("nodes").size(), 2u);
  EXPECT_EQ(summary.nodes, 2);
  // Node 0: frames 0-1 (one target), node 1: frame 2 (one target), hidden at rest.
  const json& mesh0 = g.json.at("meshes").at(g.json.at("nodes").at(0).at("mesh").get<std::size_t>());
  const json& mesh1 = g.json.at("meshes").at(g.json.at("nodes").at(1).at("mesh").get<std::size_t>());
  EXPECT_EQ(mesh0.at("primitives").at(0).at("targets").size(), 1u);
  EXPECT_EQ(mesh1.at("primitives").at(0).at("targets").size(), 1u);
  EXPECT_FALSE(g.json.at("nodes").at(0).contains("scale"));
  EXPECT_EQ(g.json.at("nodes").at(1).at("scale"), json({0.0, 0.0, 0.0}));
  // The cut topology's triangles, then the closing ones as the wound (own material, double-sided).
  ASSERT_EQ(mesh1.at("primitives").size(), 2u);
  const int64_t closing = t.closing_triangles[1];
  const std::vector<uint32_t>& cut = t.topologies[1];
  const auto tissue = g.indices(mesh1.at("primitives").at(0).at("indices").get<std::size_t>());
  const auto wound = g.indices(mesh1.at("primitives").at(1).at("indices").get<std::size_t>());
  EXPECT_EQ(tissue, std::vector<uint32_t>(cut.begin(), cut.end() - 3 * closing));
  EXPECT_EQ(wound, std::vector<uint32_t>(cut.end() - 3 * closing, cut.end()));
  const json& materials = g.json.at("materials");
  EXPECT_EQ(materials.at(mesh1.at("primitives").at(0).at("material").get<std::size_t>()).value("doubleSided", false), true);
  EXPECT_EQ(materials.at(mesh1.at("primitives").at(1).at("material").get<std::size_t>()).at("name"), "wound");
  EXPECT_EQ(materials.at(mesh0.at("primitives").at(0).at("material").get<std::size_t>()).value("doubleSided", false), false);
  EXPECT_EQ(g.indices(mesh0.at("primitives").at(0).at("indices").get<std::size_t>()), t.topologies[0]);

  // Scale channels (STEP): exactly one node shown at any time, the cut one from its frame on.
  for (std::size_t node = 0; node < 2; ++node) {
    const json* s = channel_sampler(g, node, "scale");
    ASSERT_NE(s, nullptr);
    EXPECT_EQ(s->at("interpolation"), "STEP");
  }
  for (const float time : {0.0f, 0.25f, 0.5f, 0.75f, 0.999f, 1.0f, 2.0f}) {
    const float s0 = sample(g, *channel_sampler(g, 0, "scale"), time)[0], s1 = sample(g, *channel_sampler(g, 1, "scale"), time)[0];
    EXPECT_EQ(s0 + s1, 1.0f) << time;
    EXPECT_EQ(s1, time >= 1.0f ? 1.0f : 0.0f) << time;
  }
  // Each frame's positions through the node that shows it; the old topology holds frame 1 until then.
  EXPECT_LT(max_abs_difference(morphed(g, 0, sample(g, *channel_sampler(g, 0, "weights"), 0.5f)), gltf_positions(t.frame_vertices(1), nv)), 1e-7f);
  EXPECT_EQ(sample(g, *channel_sampler(g, 0, "weights"), 0.9f), std::vector<float>{1.0f});
  EXPECT_LT(max_abs_difference(morphed(g, 1, sample(g, *channel_sampler(g, 1, "weights"), 1.0f)), gltf_positions(t.frame_vertices(2), nv)), 1e-7f);

  // A topology that comes back: a node per run, its triangles stored once.
  Trajectory back = t;
  back.time.push_back(1.5);
  back.vertices.insert(back.vertices.end(), t.vertices.begin(), t.vertices.begin() + long(3 * nv));
  back.topology_of_frame.push_back(0);
  back.spheres.insert(back.spheres.end(), 4, 0.0);
  back.blades.insert(back.blades.end(), 7, 0.0);
  const test::GltfFile g3 = export_and_read(dir.path(), "back.glb", surface, &back);
  EXPECT_TRUE(test::gltf_validates_cleanly({dir / "back.glb"}));
  ASSERT_EQ(g3.json.at("nodes").size(), 3u);
  EXPECT_EQ(g3.json.at("meshes").at(0).at("primitives").at(0).at("indices"), g3.json.at("meshes").at(2).at("primitives").at(0).at("indices"));
  for (const float time : {0.0f, 0.7f, 1.2f, 1.5f, 3.0f}) {
    float shown = 0.0f;
    for (std::size_t node = 0; node < 3; ++node) shown += sample(g3, *channel_sampler(g3, node, "scale"), time)[0];
    EXPECT_EQ(shown, 1.0f) << time;
  }
}

TEST(GltfAnimation, ASurfaceAloneIsAStillModel) {
  test::TempDir dir;
  const SurfaceMesh surface = test::bumpy_organ_surface(24, 12, 64);
  const test::GltfFile g = export_and_read(dir.path(), "still.glb", surface, nullptr);
  EXPECT_TRUE(test::gltf_validates_cleanly({dir / "still.glb"}));
  EXPECT_FALSE(g.json.contains("animations"));
  EXPECT_FALSE(g.json.at("meshes").at(0).at("primitives").at(0).contains("targets"));
  EXPECT_LT(max_abs_difference(morphed(g, 0, {}), gltf_positions(surface.vertices.data(), surface.vertices.size() / 3)), 1e-7f);
  // The normals are the file's, rotated (an undeformed surface keeps its frames exactly).
  std::vector<float> normals;
  for (std::size_t v = 0; v < surface.normals.size() / 3; ++v) {
    const auto r = lps_to_gltf_direction(&surface.normals[3 * v]);
    normals.insert(normals.end(), r.begin(), r.end());
  }
  EXPECT_EQ(morphed(g, 0, {}, "NORMAL"), normals);
}

TEST(GltfAnimation, BadInputIsRefusedNamingTheProblem) {
  const SurfaceMesh surface = test::bumpy_organ_surface(24, 12, 64);
  const Trajectory t = test::bump_trajectory(surface);
  const auto refused = [&](const fs::path& out, const Trajectory* trajectory, const GltfAnimationOptions& options,
                           const std::string& expected) {
    try {
      export_gltf_animation(out, surface, trajectory, options);
      ADD_FAILURE() << "accepted, expected an error naming " << expected;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  };
  GltfAnimationOptions named;
  named.trajectory_name = "t.h5";
  refused("a.obj", &t, named, "a.obj: suffix");
  GltfAnimationOptions scale = named;
  scale.time_scale = 0.0;
  refused("a.glb", &t, scale, "--time-scale");
  GltfAnimationOptions out_of_range = named;
  out_of_range.frames = {0, 6};
  refused("a.glb", &t, out_of_range, "out of range 0..5");
  GltfAnimationOptions unordered = named;
  unordered.frames = {2, 1};
  refused("a.glb", &t, unordered, "ascending");
  Trajectory same_time = t;
  same_time.time[2] = same_time.time[1];
  refused("a.glb", &same_time, named, "t.h5: /trajectory/time");
  Trajectory other = test::bump_trajectory(test::bumpy_organ_surface(20, 10, 64));
  refused("a.glb", &other, named, "t.h5: /trajectory/surface/rest_vertices");
  Trajectory nothing = t;
  nothing.topologies.push_back({});
  nothing.topology_of_frame[3] = 1;
  refused("a.glb", &nothing, named, "/trajectory/surface/topologies/1");
}

}  // namespace
}  // namespace ctsurg
