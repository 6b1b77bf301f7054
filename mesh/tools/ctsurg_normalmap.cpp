// ctsurg-normalmap SURFACE.h5 FIELD.h5 OUTPUT.h5: a UV atlas, tangent frames and a tangent-space
// normal map for a coarse surface, baked from the full-resolution tissue (an occupancy grid's /mask,
// anti-aliased by default, or Gaussian-smoothed with --detail gaussian) or CT (an HU volume's /hu at
// --iso), written as a ctsurg surface file, optionally a PNG and a .glb/.gltf whose material uses the
// map.
#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <optional>

#include "ctsurg/core/atomic_output.h"
#include "ctsurg/core/checked_write.h"
#include "ctsurg/core/ctsurg_file.h"
#include "ctsurg/core/error.h"
#include "ctsurg/core/hu_volume_file.h"
#include "ctsurg/core/occupancy_grid_file.h"
#include "ctsurg/core/provenance.h"
#include "ctsurg/core/surface_mesh_file.h"
#include "ctsurg/core/tool_app.h"
#include "ctsurg/core/version.h"
#include "ctsurg/core/xdmf_sidecar.h"
#include "ctsurg/mesh/detail_field.h"
#include "ctsurg/mesh/normal_map_baking.h"
#include "ctsurg/mesh/normal_map_png.h"
#include "ctsurg/mesh/surface_export.h"
#include "ctsurg/mesh/tangent_frames.h"
#include "ctsurg/mesh/uv_atlas.h"

namespace fs = std::filesystem;

namespace {

std::string suffix(const fs::path& p) {
  std::string ext = p.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

// The detail field: the tissue labels of an occupancy grid (/mask; `detail` "antialias", the default,
// or "gaussian") or an HU volume at `iso` (Gaussian only).
ctsurg::DetailField read_detail_field(const fs::path& input, std::optional<double> iso, const std::string& detail,
                                      double sigma_mm, int threads, std::string& described) {
  const std::string format = ctsurg::ctsurg_file_format(input);
  if (format == "occupancy_grid") {
    if (iso)
      throw ctsurg::InputError("--iso", "", input.string() + " is an occupancy grid: its /mask is baked at its boundary; drop --iso");
    const ctsurg::OccupancyGrid grid = ctsurg::read_occupancy_grid_file(input);
    if (detail != "gaussian") {
      ctsurg::AntiAliasOptions options;
      if (sigma_mm >= 0.0) options.sigma_mm = sigma_mm;
      options.threads = threads;
      ctsurg::AntiAliasStats stats;
      const auto start = std::chrono::steady_clock::now();
      ctsurg::DetailField field = ctsurg::detail_field_from_anti_aliased_labels(grid.mask, options, &stats);
      const auto& k = stats.blocks.factor;
      const Eigen::Vector3d native = grid.mask.geometry.spacing.cwiseProduct(Eigen::Vector3d(k[0], k[1], k[2]));
      described = fmt::format(
          "/mask (tissue != 0) anti-aliased on its {}lattice ({:.3g} x {:.3g} x {:.3g} mm), start sigma {:.3g} mm, {} "
          "iterations, {:.3f} mm off at most before the last clamp ({:.2f} s)",
          k == std::array<int, 3>{1, 1, 1} ? "" : fmt::format("own {} x {} x {} blocks' ", k[0], k[1], k[2]), native[0],
          native[1], native[2], sigma_mm >= 0.0 ? sigma_mm : ctsurg::kDefaultSigmaVoxels * native.maxCoeff(), stats.iterations,
          stats.last_violation_mm, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      return field;
    }
    const double sigma = sigma_mm >= 0.0 ? sigma_mm : grid.mask.geometry.spacing.maxCoeff();
    described = fmt::format("/mask (tissue != 0), Gaussian sigma {:.3g} mm, iso 0.5", sigma);
    return ctsurg::detail_field_from_labels(grid.mask, sigma, threads);
  }
  if (format == "hu_volume") {
    if (detail == "antialias")
      throw ctsurg::InputError("--detail", "", input.string() + " is an HU volume: its detail is Gaussian-smoothed; antialias is for masks");
    if (!iso) throw ctsurg::InputError("--iso", "", input.string() + " is an HU volume: give the isovalue in HU, e.g. --iso 150");
    const ctsurg::HuVolume hu = ctsurg::read_hu_volume_file(input);
    const double sigma = sigma_mm >= 0.0 ? sigma_mm : hu.hu.geometry.spacing.maxCoeff();
    described = fmt::format("/hu, Gaussian sigma {:.3g} mm, iso {} HU", sigma, *iso);
    return ctsurg::detail_field_from_values(hu.hu, *iso, sigma, threads);
  }
  throw ctsurg::InputError(input.string(), "/@ctsurg_format",
                           "expected an occupancy grid (ctsurg-grid) or an HU volume (ctsurg-import), found '" +
                               (format.empty() ? std::string("none") : format) + "'");
}

// A surface baked from a field it does not lie in would read clamped edge values everywhere: the
// two files must come from the same patient and frame. Refused when no vertex lies in the field's
// lattice; a warning when some lie more than a voxel outside it.
void check_overlap(const ctsurg::SurfaceMesh& surface, const std::string& surface_path, const ctsurg::DetailField& field,
                   const std::string& field_path) {
  const auto& g = field.values.geometry;
  int64_t inside = 0;
  for (int64_t v = 0; v < surface.vertex_count(); ++v) {
    const Eigen::Vector3d p(surface.vertices[3 * v], surface.vertices[3 * v + 1], surface.vertices[3 * v + 2]);
    const Eigen::Vector3d x = field.world_to_index_linear * (p - g.origin);
    bool in = true;
    for (int a = 0; a < 3; ++a) in = in && x[a] >= -1.0 && x[a] <= static_cast<double>(g.dims[static_cast<std::size_t>(a)]);
    inside += in ? 1 : 0;
  }
  if (inside == 0) {
    throw ctsurg::InputError(field_path, "geometry",
                             "the surface " + surface_path + " lies entirely outside this field's lattice: the two files "
                             "are not of the same patient and frame");
  }
  if (inside < surface.vertex_count()) {
    spdlog::warn("{}: {} of {} vertices of {} lie outside the field's lattice; their detail comes from its edge",
                 field_path, surface.vertex_count() - inside, surface.vertex_count(), surface_path);
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::string surface_path, field_path, output, png_path, mesh_path, detail;
  double iso = 0.0, sigma_mm = -1.0, search_mm = 0.0, max_angle_deg = 60.0;
  int size = 2048, bits = 8, padding = 4, dilate = 2, threads = 0;
  CLI::Option* iso_opt = nullptr;
  return ctsurg::run_tool(
      argc, argv, "ctsurg-normalmap",
      "Bake the full-resolution detail onto a coarse surface (from ctsurg-surface): a UV atlas (planar charts, "
      "uniform texel density, packed with padding), glTF tangents and a tangent-space normal map from the gradient "
      "of the smoothed full-resolution field where it crosses the surface nearest along the normal. FIELD is an "
      "occupancy grid (its /mask) or an HU volume (--iso HU). Writes OUTPUT.h5 (surface + uvs, tangents, "
      "source_vertex, normal map), optionally --png and --mesh (.glb/.gltf with the map as normalTexture).",
      [&](CLI::App& app) {
        app.add_option("surface", surface_path, "Surface file from ctsurg-surface (.h5)")->required();
        app.add_option("field", field_path, "Occupancy grid (ctsurg-grid) or HU volume (ctsurg-import) file (.h5)")->required();
        app.add_option("output", output, "Surface file to write (.h5)")->required();
        app.add_option("--png", png_path, "Also write the normal map as a PNG");
        app.add_option("--mesh,--glb", mesh_path, "Also write the textured mesh: .glb or .gltf (normal map embedded)");
        app.add_option("--size", size, "Atlas and map size in texels (width = height)")
            ->capture_default_str()
            ->check(CLI::Range(16, 16384));
        app.add_option("--bits", bits, "Bits per channel: 8 or 16")->capture_default_str()->check(CLI::IsMember({8, 16}));
        app.add_option("--padding", padding, "Empty texels between charts")->capture_default_str()->check(CLI::Range(1, 256));
        app.add_option("--dilate", dilate, "Texels the charts are dilated into the padding")
            ->capture_default_str()
            ->check(CLI::Range(0, 64));
        app.add_option("--detail", detail,
                       "The mask's detail field: antialias (default: smooth, every voxel on its side, on the mask's own "
                       "lattice) or gaussian (the indicator smoothed by --sigma-mm); HU volumes: gaussian only");
        app.add_option("--sigma-mm", sigma_mm,
                       "Gaussian smoothing, mm: antialias: of its start field (default: 2 of the mask's own voxels); "
                       "gaussian: of the whole field (default: its largest voxel spacing)")
            ->check(CLI::NonNegativeNumber);
        iso_opt = app.add_option("--iso", iso, "Isovalue in HU (HU volumes only)");
        app.add_option("--search-mm", search_mm, "Search range along the normal, mm (default: one grid cell)")
            ->check(CLI::NonNegativeNumber);
        app.add_option("--max-angle-deg", max_angle_deg, "Largest angle between a chart's axis and its triangles' normals")
            ->capture_default_str()
            ->check(CLI::Range(1.0, 85.0));
        app.add_option("--threads", threads, "OpenMP threads (0: all)")->check(CLI::Range(0, 1024));
      },
      [&](const ctsurg::ToolContext& ctx) {
        const auto start = std::chrono::steady_clock::now();
        const fs::path out_path = output;
        if (suffix(out_path) != ".h5" && suffix(out_path) != ".hdf5") {
          throw ctsurg::InputError(output, "suffix", "the output is a ctsurg surface file: use .h5");
        }
        if (!png_path.empty() && suffix(png_path) != ".png")
          throw ctsurg::InputError(png_path, "suffix", "--png needs a .png name");
        if (!mesh_path.empty() && suffix(mesh_path) != ".glb" && suffix(mesh_path) != ".gltf") {
          throw ctsurg::InputError(mesh_path, "suffix", "--mesh needs a .glb or .gltf name");
        }
        if (padding > size / 8) throw ctsurg::InputError("--padding", "", "must be at most --size / 8");
        if (*iso_opt && !std::isfinite(iso)) throw ctsurg::InputError("--iso", "", "must be a finite number");
        if (!detail.empty() && detail != "antialias" && detail != "gaussian")
          throw ctsurg::InputError("--detail", "", "'" + detail + "': use antialias or gaussian");
        {
          std::vector<fs::path> outputs{out_path, ctsurg::xdmf_path_for(out_path)};
          if (!png_path.empty()) outputs.emplace_back(png_path);
          if (!mesh_path.empty()) {
            for (const auto& f : ctsurg::surface_export_files(mesh_path, true)) outputs.push_back(f);
          }
          ctsurg::check_output_paths(outputs, {fs::path(surface_path), fs::path(field_path)});
        }

        const ctsurg::SurfaceMesh coarse = ctsurg::read_surface_mesh_file(surface_path);
        if (!coarse.uvs.empty()) {
          throw ctsurg::InputError(surface_path, "/surface/uvs",
                                   "already has a texture atlas; give the surface from ctsurg-surface");
        }
        std::string described;
        const ctsurg::DetailField field =
            read_detail_field(field_path, *iso_opt ? std::optional<double>(iso) : std::nullopt, detail, sigma_mm, threads, described);
        check_overlap(coarse, surface_path, field, field_path);
        spdlog::info("{}: {} vertices, {} triangles; detail from {}: {}", surface_path, coarse.vertex_count(),
                     coarse.triangle_count(), field_path, described);

        const auto seconds_since = [](std::chrono::steady_clock::time_point t) {
          return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
        };
        const auto atlas_start = std::chrono::steady_clock::now();
        const ctsurg::UvAtlas atlas = ctsurg::build_uv_atlas(coarse.vertices, coarse.triangles, {size, padding, max_angle_deg});
        ctsurg::SurfaceMesh mesh = ctsurg::apply_uv_atlas(coarse, atlas);
        mesh.tangents = ctsurg::tangent_frames(mesh.vertices, mesh.normals, mesh.triangles, mesh.uvs);
        spdlog::info("atlas: {} charts, {} x {} texels, {:.3f} mm per texel, fill {:.1f} %, {} vertices after seams ({:.2f} s)",
                     atlas.chart_count, size, size, 1.0 / atlas.texels_per_mm, 100.0 * atlas.fill_ratio, mesh.vertex_count(),
                     seconds_since(atlas_start));
        ctsurg::NormalMapBakeStats stats;
        const auto bake_start = std::chrono::steady_clock::now();
        mesh.normal_map = ctsurg::bake_normal_map(mesh, field, {size, bits, dilate, search_mm, threads}, &stats);
        spdlog::info(
            "normal map: {} texels baked ({:.1f} % on a detailed-surface crossing within {:.2f} mm), {} dilated, "
            "mean tilt from the coarse normal {:.2f} deg ({:.2f} s)",
            stats.texels_covered, stats.texels_covered ? 100.0 * stats.texels_on_crossing / stats.texels_covered : 0.0,
            stats.search_mm, stats.texels_dilated, stats.mean_tilt_deg, seconds_since(bake_start));

        // Every output goes to a temporary name first, and all are committed together.
        const std::vector<uint8_t> png = ctsurg::encode_normal_map_png(mesh.normal_map);
        ctsurg::OutputUnit outputs;
        if (!png_path.empty()) {
          ctsurg::AtomicOutput& png_out = outputs.add(png_path);
          ctsurg::write_file_checked(png_out.temp_path(),
                                     std::string_view(reinterpret_cast<const char*>(png.data()), png.size()), png_path);
        }
        if (!mesh_path.empty()) ctsurg::add_surface_export(outputs, mesh_path, mesh, png);
        ctsurg::Provenance provenance{ctx.name, ctsurg::kVersion, ctx.command_line, {}, nlohmann::json::array()};
        provenance.add_input(surface_path);
        provenance.add_input(field_path);
        ctsurg::write_surface_mesh_file(out_path, mesh, provenance, &outputs);
        outputs.commit();
        spdlog::info("wrote {} in {:.2f} s", output,
                     std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      });
}
