// ctsurg-normalmap as a user runs it: a ridged ball as an occupancy grid (2 mm cells, tissue mask at
// 1 mm), its surface from ctsurg-surface, then the normal map tool's .h5 / .png / .glb / .gltf
// outputs (glTF: valid by the Khronos validator, in glTF's frame with rotated normals and tangents),
// --detail (anti-aliased mask by default, Gaussian on request), determinism and bad-input handling
// (exit 2, a message naming the problem, no file left).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "ctsurg/core/hu_volume_file.h"
#include "ctsurg/core/occupancy_grid_file.h"
#include "ctsurg/core/provenance.h"
#include "ctsurg/core/surface_mesh_file.h"
#include "ctsurg/mesh/normal_map_baking.h"
#include "ctsurg/mesh/normal_map_png.h"
#include "gltf_checks.h"
#include "test_support.h"

namespace fs = std::filesystem;
using ctsurg::test::run_tool;
using ctsurg::test::TempDir;

namespace {

using ctsurg::test::test_provenance;

// Inside the ball of radius 12 mm with 8 ridges around z of 0.8 mm.
bool inside(const Eigen::Vector3d& p) { return p.norm() <= 12.0 + 0.8 * std::cos(8.0 * std::atan2(p.y(), p.x())); }

// The occupancy grid: fractions on 2 mm cells by 4^3 supersampling, the mask at 1 mm.
fs::path write_grid(const TempDir& dir) {
  ctsurg::ImageGeometry g;
  g.dims = {17, 17, 17};
  g.spacing = Eigen::Vector3d::Constant(2.0);
  g.origin = Eigen::Vector3d(-16.0, -16.0, -16.0);
  ctsurg::OccupancyGrid grid;
  grid.fraction = ctsurg::Volume<float>(g, 0.0f);
  grid.occupancy = ctsurg::Volume<uint8_t>(g, 0);
  grid.label = ctsurg::Volume<uint16_t>(g, 0);
  constexpr int s = 4;
  for (int64_t k = 0; k < 17; ++k)
    for (int64_t j = 0; j < 17; ++j)
      for (int64_t i = 0; i < 17; ++i) {
        int in = 0;
        for (int c = 0; c < s * s * s; ++c) {
          const Eigen::Vector3d sub((c % s + 0.5) / s - 0.5, ((c / s) % s + 0.5) / s - 0.5, (c / (s * s) + 0.5) / s - 0.5);
          in += inside(g.index_to_world(Eigen::Vector3d(double(i), double(j), double(k)) + sub));
        }
        grid.fraction(i, j, k) = float(in) / (s * s * s);
        grid.occupancy(i, j, k) = grid.label(i, j, k) = grid.fraction(i, j, k) >= 0.5f;
      }
  ctsurg::ImageGeometry m;
  m.dims = {33, 33, 33};
  m.spacing = Eigen::Vector3d::Constant(1.0);
  m.origin = Eigen::Vector3d(-16.0, -16.0, -16.0);
  grid.mask = ctsurg::Volume<uint16_t>(m, 0);
  for (int64_t k = 0; k < 33; ++k)
    for (int64_t j = 0; j < 33; ++j)
      for (int64_t i = 0; i < 33; ++i)
        grid.mask(i, j, k) = inside(m.index_to_world(Eigen::Vector3d(double(i), double(j), double(k))));
  grid.label_names = {{1, "ball"}};
  const fs::path p = dir / "grid.h5";
  ctsurg::write_occupancy_grid_file(p, grid, test_provenance());
  return p;
}

using ctsurg::test::read_bytes;

// The JSON chunk of a .glb (binary glTF 2: 12-byte header, then a chunk of length, type "JSON", data).
nlohmann::json glb_json(const std::string& glb) {
  uint32_t length = 0;
  std::memcpy(&length, glb.data() + 12, 4);
  EXPECT_EQ(glb.substr(16, 4), "JSON");
  return nlohmann::json::parse(glb.substr(20, length));
}

// The material's normalTexture leads to a PNG image, and the mesh has UVs. Returns the image.
nlohmann::json expect_normal_textured(const nlohmann::json& j) {
  EXPECT_TRUE(j["meshes"][0]["primitives"][0]["attributes"].contains("TEXCOORD_0"));
  EXPECT_TRUE(j["meshes"][0]["primitives"][0]["attributes"].contains("TANGENT"));
  if (!j.contains("materials") || !j["materials"][0].contains("normalTexture")) {
    ADD_FAILURE() << "no normalTexture: " << j.dump();
    return {};
  }
  const auto& tex = j["textures"][j["materials"][0]["normalTexture"]["index"].get<std::size_t>()];
  return j["images"][tex["source"].get<std::size_t>()];
}

// The .glb/.gltf at `path` passes the Khronos validator, declares no extension, and holds the
// vertices of `m` (the .h5 the same run wrote) in glTF's frame (docs/formats.md): each exported
// vertex is an .h5 vertex with the same uv at (x, z, -y) / 1000 m, its NORMAL and TANGENT xyz rotated
// the same way and TANGENT w (handedness) unchanged.
void expect_gltf_frame(const fs::path& path, const ctsurg::SurfaceMesh& m) {
  EXPECT_TRUE(ctsurg::test::gltf_validates({path}));
  const auto gltf = ctsurg::test::read_gltf(path);
  EXPECT_FALSE(gltf.json.contains("extensionsUsed")) << path << ": " << gltf.json["extensionsUsed"].dump();
  EXPECT_EQ(gltf.json.dump().find("\"extensions\""), std::string::npos) << path;
  const std::vector<float> p = gltf.floats(gltf.attribute("POSITION")), n = gltf.floats(gltf.attribute("NORMAL")),
                           t = gltf.floats(gltf.attribute("TANGENT")), uv = gltf.floats(gltf.attribute("TEXCOORD_0"));
  ASSERT_EQ(p.size() / 3, t.size() / 4) << path;
  ASSERT_EQ(p.size() / 3, uv.size() / 2) << path;
  const auto rotate = [](const float* a) { return Eigen::Vector3d(a[0], a[2], -a[1]); };
  int unmatched = 0, wrong = 0;
  for (std::size_t v = 0; v < p.size() / 3; ++v) {
    const Eigen::Vector3d pv(p[3 * v], p[3 * v + 1], p[3 * v + 2]);
    std::size_t u = 0;
    for (; u < static_cast<std::size_t>(m.vertex_count()); ++u) {
      if ((rotate(&m.vertices[3 * u]) / 1000.0 - pv).norm() < 1e-7 && std::abs(m.uvs[2 * u] - uv[2 * v]) < 1e-6f &&
          std::abs(m.uvs[2 * u + 1] - uv[2 * v + 1]) < 1e-6f)
        break;
    }
    if (u == static_cast<std::size_t>(m.vertex_count())) {
      ++unmatched;
      continue;
    }
    const Eigen::Vector3d nv(n[3 * v], n[3 * v + 1], n[3 * v + 2]), tv(t[4 * v], t[4 * v + 1], t[4 * v + 2]);
    wrong += (nv - rotate(&m.normals[3 * u])).norm() > 1e-6 || (tv - rotate(&m.tangents[4 * u])).norm() > 1e-6 ||
             t[4 * v + 3] != m.tangents[4 * u + 3] || std::abs(nv.dot(tv)) > 1e-3;
  }
  EXPECT_EQ(unmatched, 0) << path;
  EXPECT_EQ(wrong, 0) << path;
}

struct Outputs {
  fs::path grid, surface;
};

Outputs prepare(const TempDir& dir) {
  Outputs o{write_grid(dir), dir / "surface.h5"};
  const auto r = run_tool("ctsurg-surface", {o.grid.string(), o.surface.string()});
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return o;
}

TEST(CtsurgNormalmap, WritesSurfacePngAndGlbWithTheNormalTexture) {
  TempDir dir;
  const Outputs in = prepare(dir);
  const auto r = run_tool("ctsurg-normalmap", {in.surface.string(), in.grid.string(), (dir / "nm.h5").string(), "--size", "256",
                                               "--png", (dir / "nm.png").string(), "--mesh", (dir / "nm.glb").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("charts"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("anti-aliased"), std::string::npos) << r.output;  // the default detail field
  const auto coarse = ctsurg::read_surface_mesh_file(in.surface);
  const auto m = ctsurg::read_surface_mesh_file(dir / "nm.h5");
  EXPECT_EQ(m.triangle_count(), coarse.triangle_count());
  EXPECT_GE(m.vertex_count(), coarse.vertex_count());
  EXPECT_EQ(m.uvs.size(), 2 * m.vertices.size() / 3);
  EXPECT_EQ(m.tangents.size(), 4 * m.vertices.size() / 3);
  EXPECT_EQ(m.source_vertex_count, coarse.vertex_count());
  ASSERT_EQ(m.normal_map.width, 256);
  EXPECT_EQ(m.normal_map.bits, 8);
  // The grid tie travels with the copies.
  for (std::size_t v = 0; v < m.source_vertex.size(); ++v)
    for (int c = 0; c < 8; ++c)
      ASSERT_EQ(m.grid_weights[8 * v + std::size_t(c)], coarse.grid_weights[8 * m.source_vertex[v] + std::size_t(c)]);
  // The PNG holds the same map as the .h5; the ridges tilt the normals, so the map is not flat.
  const std::string png = read_bytes(dir / "nm.png");
  const auto decoded = ctsurg::decode_normal_map_png(std::vector<uint8_t>(png.begin(), png.end()), "nm.png");
  EXPECT_EQ(decoded.rgb, m.normal_map.rgb);
  int64_t tilted = 0;  // normals more than about 9 deg off the coarse normal
  for (std::size_t i = 0; i < decoded.rgb.size(); i += 3)
    tilted += std::abs(decoded.rgb[i] - 128) > 20 || std::abs(decoded.rgb[i + 1] - 128) > 20;
  EXPECT_GT(tilted, 1000);
  const std::string glb = read_bytes(dir / "nm.glb");
  ASSERT_EQ(glb.substr(0, 4), "glTF");
  const auto img = expect_normal_textured(glb_json(glb));
  EXPECT_EQ(img.value("mimeType", ""), "image/png");
  EXPECT_TRUE(img.contains("bufferView")) << img.dump();
  // The PNG is embedded byte for byte.
  EXPECT_NE(glb.find(png.substr(0, 4096)), std::string::npos);
  expect_gltf_frame(dir / "nm.glb", m);
  for (const auto& f : ctsurg::test::files_in(dir.path()))
    EXPECT_EQ(f.filename().string().rfind(".tmp-", 0), std::string::npos) << f;
}

TEST(CtsurgNormalmap, GltfWritesBinBesideIt16Bit) {
  TempDir dir;
  const Outputs in = prepare(dir);
  const auto r = run_tool("ctsurg-normalmap", {in.surface.string(), in.grid.string(), (dir / "nm.h5").string(), "--size", "128",
                                               "--bits", "16", "--mesh", (dir / "nm.gltf").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ASSERT_TRUE(fs::exists(dir / "nm.bin"));
  const auto j = nlohmann::json::parse(read_bytes(dir / "nm.gltf"));
  EXPECT_EQ(expect_normal_textured(j).value("uri", ""), "nm_normal_map.png");
  EXPECT_EQ(j["buffers"][0]["uri"], "nm.bin");
  const std::string png = read_bytes(dir / "nm_normal_map.png");
  const auto map = ctsurg::decode_normal_map_png(std::vector<uint8_t>(png.begin(), png.end()), "nm_normal_map.png");
  EXPECT_EQ(map.bits, 16);
  EXPECT_EQ(map.width, 128);
  const auto m = ctsurg::read_surface_mesh_file(dir / "nm.h5");
  EXPECT_EQ(m.normal_map.bits, 16);
  expect_gltf_frame(dir / "nm.gltf", m);
  for (const auto& f : ctsurg::test::files_in(dir.path()))
    EXPECT_EQ(f.filename().string().rfind(".tmp-", 0), std::string::npos) << f;
}

TEST(CtsurgNormalmap, RerunIsByteIdentical) {
  TempDir dir;
  const Outputs in = prepare(dir);
  const std::vector<std::string> args = {
      in.surface.string(),      in.grid.string(), (dir / "a.h5").string(),  "--size",    "128", "--png",
      (dir / "a.png").string(), "--mesh",         (dir / "a.glb").string(), "--threads", "1"};
  ASSERT_EQ(run_tool("ctsurg-normalmap", args).exit_code, 0);
  const std::string h5 = read_bytes(dir / "a.h5"), png = read_bytes(dir / "a.png"), glb = read_bytes(dir / "a.glb");
  ASSERT_EQ(run_tool("ctsurg-normalmap", args).exit_code, 0);
  EXPECT_TRUE(read_bytes(dir / "a.h5") == h5);
  EXPECT_TRUE(read_bytes(dir / "a.png") == png);
  EXPECT_TRUE(read_bytes(dir / "a.glb") == glb);
  // Another thread count: the same map (the .h5 differs only in the recorded command line).
  ASSERT_EQ(run_tool("ctsurg-normalmap", {in.surface.string(), in.grid.string(), (dir / "b.h5").string(), "--size", "128",
                                          "--png", (dir / "b.png").string(), "--threads", "2"})
                .exit_code,
            0);
  EXPECT_TRUE(read_bytes(dir / "b.png") == png);
}

// --detail: the anti-aliased mask by default, the Gaussian-smoothed one on request (the old
// default); the default map is the closer one to the ridged ball's analytic normals.
TEST(CtsurgNormalmap, DetailOptionChoosesTheMasksField) {
  TempDir dir;
  const Outputs in = prepare(dir);
  const auto run = [&](const std::string& name, std::vector<std::string> extra) {
    std::vector<std::string> args = {in.surface.string(), in.grid.string(), (dir / (name + ".h5")).string(), "--size", "256",
                                     "--png", (dir / (name + ".png")).string()};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto r = run_tool("ctsurg-normalmap", args);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return r.output;
  };
  const std::string by_default = run("default", {}), antialias = run("antialias", {"--detail", "antialias"}),
                    gaussian = run("gaussian", {"--detail", "gaussian"});
  EXPECT_NE(by_default.find("anti-aliased"), std::string::npos) << by_default;
  EXPECT_NE(gaussian.find("Gaussian sigma 1 mm"), std::string::npos) << gaussian;
  EXPECT_TRUE(read_bytes(dir / "default.png") == read_bytes(dir / "antialias.png"));
  const auto decode = [&](const std::string& name) {
    const std::string png = read_bytes(dir / (name + ".png"));
    return ctsurg::decode_normal_map_png(std::vector<uint8_t>(png.begin(), png.end()), name);
  };
  // Against the ridged ball's analytic normals, at every covered texel away from the poles (where
  // the ridges meet and the surface is singular): the baked normal through the texel's interpolated
  // frame, the truth where the radial line through the texel's point meets the ridged surface.
  const auto m = ctsurg::read_surface_mesh_file(dir / "antialias.h5");
  const auto owner = ctsurg::texel_owners(m.uvs, m.triangles, 256);
  const auto error_deg = [&](const std::string& name) {
    const auto map = decode(name);
    double sum = 0.0;
    int64_t count = 0;
    for (int y = 0; y < 256; ++y)
      for (int x = 0; x < 256; ++x) {
        const int32_t t = owner[std::size_t(y) * 256 + std::size_t(x)];
        if (t < 0) continue;
        const uint32_t* v = &m.triangles[3 * std::size_t(t)];
        Eigen::Vector2d q[3];
        for (int c = 0; c < 3; ++c) q[c] = Eigen::Vector2d(m.uvs[2 * v[c]] * 256.0, m.uvs[2 * v[c] + 1] * 256.0);
        const auto cross2 = [](const Eigen::Vector2d& a2, const Eigen::Vector2d& b2) { return a2.x() * b2.y() - a2.y() * b2.x(); };
        const Eigen::Vector2d px(x + 0.5, y + 0.5);
        const double area = cross2(q[1] - q[0], q[2] - q[0]);
        double l[3] = {0.0, cross2(px - q[0], q[2] - q[0]) / area, cross2(q[1] - q[0], px - q[0]) / area};
        l[0] = 1.0 - l[1] - l[2];
        Eigen::Vector3d P = Eigen::Vector3d::Zero(), N = P, T = P;
        double w = 0.0;
        for (int c = 0; c < 3; ++c) {
          const double lc = std::max(l[c], 0.0);
          for (int k = 0; k < 3; ++k) {
            P[k] += lc * m.vertices[3 * v[c] + k];
            N[k] += lc * m.normals[3 * v[c] + k];
            T[k] += lc * m.tangents[4 * v[c] + k];
          }
          w += lc * m.tangents[4 * v[c] + 3];
        }
        N.normalize();
        T = (T - N * N.dot(T)).normalized();
        const Eigen::Vector3d B = (w < 0 ? -1.0 : 1.0) * N.cross(T), ts = ctsurg::decode_normal_map_texel(map, x, y);
        const Eigen::Vector3d baked = ts.x() * T + ts.y() * B + ts.z() * N, d = P.normalized();
        if (std::abs(d.z()) > 0.7) continue;
        const double phi = std::atan2(d.y(), d.x());
        const Eigen::Vector3d s3 = (12.0 + 0.8 * std::cos(8.0 * phi)) * d;
        const double rho2 = s3.x() * s3.x() + s3.y() * s3.y();
        const Eigen::Vector3d truth = (d + 6.4 * std::sin(8.0 * phi) * Eigen::Vector3d(-s3.y(), s3.x(), 0.0) / rho2).normalized();
        sum += std::atan2(baked.cross(truth).norm(), baked.dot(truth)) * 180.0 / std::numbers::pi;
        ++count;
      }
    EXPECT_GT(count, 5000);
    return sum / double(count);
  };
  const double err_aa = error_deg("antialias"), err_g = error_deg("gaussian");
  std::printf("ridged ball, mean normal error away from the poles: antialias %.2f deg, gaussian %.2f deg\n", err_aa, err_g);
  EXPECT_LT(err_aa, 0.8 * err_g);
}

TEST(CtsurgNormalmap, BadInputExitsTwoAndLeavesNoFile) {
  TempDir dir;
  const Outputs in = prepare(dir);
  ctsurg::HuVolume v;
  ctsurg::ImageGeometry g;
  g.dims = {8, 8, 8};
  v.hu = ctsurg::Volume<float>(g, -1000.0f);
  ctsurg::write_hu_volume_file(dir / "ct.h5", v, test_provenance());
  ASSERT_EQ(
      run_tool("ctsurg-normalmap", {in.surface.string(), in.grid.string(), (dir / "done.h5").string(), "--size", "64"}).exit_code,
      0);
  const auto expect_bad = [&](const std::vector<std::string>& args, const std::string& says) {
    const auto before = ctsurg::test::files_in(dir.path());
    const auto r = run_tool("ctsurg-normalmap", args);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(says), std::string::npos) << r.output;
    EXPECT_EQ(ctsurg::test::files_in(dir.path()), before) << r.output;
  };
  const std::string s = in.surface.string(), grid = in.grid.string(), out = (dir / "o.h5").string();
  const std::string png = (dir / "o.png").string(), glb = (dir / "o.glb").string();
  expect_bad({s, (dir / "ct.h5").string(), out, "--png", png, "--mesh", glb}, "--iso");
  expect_bad({s, grid, out, "--bits", "12", "--png", png}, "--bits");
  expect_bad({s, grid, out, "--png", (dir / "o.jpg").string()}, "--png");
  expect_bad({s, grid, (dir / "o.vtk").string()}, "suffix");
  expect_bad({s, grid, out, "--mesh", (dir / "o.stl").string()}, "--mesh");
  expect_bad({(dir / "missing.h5").string(), grid, out, "--png", png}, "missing.h5");
  expect_bad({grid, grid, out, "--png", png}, "surface_mesh");
  expect_bad({(dir / "done.h5").string(), grid, out, "--png", png}, "already has a texture atlas");
  expect_bad({s, grid, (dir / "no_such_folder" / "o.h5").string()}, "no_such_folder");
  expect_bad({s, grid, out, "--size", "64", "--padding", "9"}, "--padding");
  // Issue 17: --sigma-mm 1e9 and --threads 1000000 crashed; outputs that are inputs replaced them;
  // a surface and a field that do not overlap were accepted.
  expect_bad({s, grid, out, "--sigma-mm", "1e9"}, "--sigma-mm");
  expect_bad({s, grid, out, "--sigma-mm", "1e9", "--detail", "gaussian"}, "--sigma-mm");
  expect_bad({s, grid, out, "--detail", "median", "--png", png}, "--detail");
  expect_bad({s, (dir / "ct.h5").string(), out, "--iso", "0", "--detail", "antialias"}, "--detail");
  expect_bad({s, grid, out, "--threads", "1000000"}, "--threads");
  expect_bad({s, grid, s}, "is the input");
  expect_bad({s, grid, grid}, "is the input");
  v.hu.geometry.origin = Eigen::Vector3d(500.0, 500.0, 500.0);
  ctsurg::write_hu_volume_file(dir / "far.h5", v, test_provenance());
  expect_bad({s, (dir / "far.h5").string(), out, "--iso", "0"}, "lies entirely outside this field");
}

// Issue 17: a corrupted HDF5 surface crashed libhdf5 in normalmap (and sim, render). Bytes flipped
// across the file: every run is refused (exit 2) or, where a byte is unused, succeeds; none crashes.
TEST(CtsurgNormalmap, ACorruptedSurfaceFileIsRefusedNeverCrashes) {
  TempDir dir;
  const Outputs in = prepare(dir);
  const std::string bytes = read_bytes(in.surface);
  int refused = 0;
  for (int n = 1; n <= 12; ++n) {
    std::string bad = bytes;
    const std::size_t at = bytes.size() * static_cast<std::size_t>(n) / 13;
    for (std::size_t b = at; b < std::min(bytes.size(), at + 8); ++b) bad[b] = static_cast<char>(~bad[b]);
    { std::ofstream(dir / "bad.h5", std::ios::binary) << bad; }
    const auto r = run_tool("ctsurg-normalmap", {(dir / "bad.h5").string(), in.grid.string(), (dir / "o.h5").string(),
                                                 "--size", "64"});
    EXPECT_TRUE(r.exit_code == 2 || r.exit_code == 0) << "bytes " << at << "..: exit " << r.exit_code << "\n" << r.output;
    refused += r.exit_code == 2;
  }
  EXPECT_GE(refused, 10);
}

}  // namespace
