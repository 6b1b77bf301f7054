// ctsurg-surface INPUT.h5 OUTPUT: the isosurface of an occupancy grid's volume fractions (or of an
// HU volume) by marching cubes, as a ctsurg surface file (.h5 + XDMF) or a mesh for other programs
// (.glb, .gltf, .obj, .stl, .ply, and .vtk/.vtp for 3D Slicer).
#include "ctsurg/core/atomic_output.h"
#include "ctsurg/core/ctsurg_file.h"
#include "ctsurg/core/error.h"
#include "ctsurg/core/hu_volume_file.h"
#include "ctsurg/core/occupancy_grid_file.h"
#include "ctsurg/core/provenance.h"
#include "ctsurg/core/surface_mesh_file.h"
#include "ctsurg/core/tool_app.h"
#include "ctsurg/core/version.h"
#include "ctsurg/core/xdmf_sidecar.h"
#include "ctsurg/mesh/degenerate_triangles.h"
#include "ctsurg/mesh/lattice_padding.h"
#include "ctsurg/mesh/lattice_tie.h"
#include "ctsurg/mesh/marching_cubes.h"
#include "ctsurg/mesh/surface_decimation.h"
#include "ctsurg/mesh/surface_smoothing.h"
#include "ctsurg/mesh/surface_export.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace fs = std::filesystem;

namespace {

struct Field {
  ctsurg::Volume<float> volume;
  std::string quantity, dataset;
};

// The field to contour: /grid/fraction of an occupancy grid file or /hu of an HU volume file.
Field read_field(const fs::path& input) {
  const std::string format = ctsurg::ctsurg_file_format(input);
  if (format == "occupancy_grid") return {ctsurg::read_occupancy_grid_file(input).fraction, "fraction", "/grid/fraction"};
  if (format == "hu_volume") return {ctsurg::read_hu_volume_file(input).hu, "HU", "/hu"};
  throw ctsurg::InputError(input.string(), "/@ctsurg_format",
                           "expected an occupancy grid (ctsurg-grid) or an HU volume (ctsurg-import), found '" +
                               (format.empty() ? std::string("none") : format) + "'");
}

}  // namespace

int main(int argc, char** argv) {
  std::string input, output;
  double iso = 0.5;
  int threads = 0;
  int smooth = 20;
  std::string smooth_method = "sinc";
  double pass_band = 0.0;  // when not given: the method's default
  bool raw = false;
  int64_t decimate = 0;
  bool open_border = false;
  CLI::Option* iso_opt = nullptr;
  CLI::Option* band_opt = nullptr;
  return ctsurg::run_tool(
      argc, argv, "ctsurg-surface",
      "Extract the organ surface by marching cubes (closed, consistently oriented, shared vertices, each vertex "
      "tied to its grid cell): from an occupancy grid's volume fractions (default iso 0.5) or an HU volume "
      "(--iso HU). Degenerate triangles are removed; the surface is then smoothed (windowed sinc, 20 iterations, "
      "as 3D Slicer's segmentation export) with its enclosed volume restored, unless --raw. Output by suffix: .h5 "
      "(ctsurg surface + XDMF), .glb, .gltf, .obj, .stl, .ply, .vtk, .vtp (3D Slicer: SPACE=LPS); LPS mm.",
      [&](CLI::App& app) {
        app.add_option("input", input, "Occupancy grid (ctsurg-grid) or HU volume (ctsurg-import) file (.h5)")->required();
        app.add_option("output", output, "Surface to write: .h5, .glb, .gltf, .obj, .stl, .ply, .vtk or .vtp")->required();
        iso_opt = app.add_option("--iso", iso, "Isovalue: volume fraction for a grid (default 0.5), HU for an HU volume (required)");
        app.add_option("--threads", threads, "OpenMP threads (0: all)")->check(CLI::Range(0, 1024));
        auto* smooth_opt =
            app.add_option("--smooth", smooth,
                           "Smoothing iterations: the windowed sinc's Chebyshev order (Laplacian applications), or "
                           "Taubin's lambda|mu pairs; 0: off (as --raw)")
                ->capture_default_str()
                ->check(CLI::Range(0, 1000));
        auto* method_opt =
            app.add_option("--smooth-method", smooth_method,
                           "sinc: windowed-sinc low-pass filter, pass band 0.01 (3D Slicer's smoothing factor 0.5); "
                           "taubin: lambda 0.5, pass band 0.1. Either way the enclosed volume is restored (closed surfaces)")
                ->capture_default_str()
                ->check(CLI::IsMember({"sinc", "taubin"}));
        band_opt = app.add_option("--pass-band", pass_band,
                                  "Low-pass filter's pass band kPB in (0, 2), in Laplacian eigenvalues (default: sinc 0.01, "
                                  "taubin 0.1; larger keeps more detail)");
        app.add_flag("--raw", raw, "Keep the marching-cubes surface unsmoothed (degenerate triangles are still removed)")
            ->excludes(smooth_opt)
            ->excludes(method_opt)
            ->excludes(band_opt);
        app.add_option("--decimate", decimate, "Quadric edge-collapse decimation to about this many triangles; 0: off")
            ->check(CLI::NonNegativeNumber);
        app.add_flag("--open-border", open_border,
                     "Leave the surface open where the tissue touches the lattice border (default: close it with a "
                     "one-node frame of outside values, which moves the stored lattice by one node)");
      },
      [&](const ctsurg::ToolContext& ctx) {
        const auto start = std::chrono::steady_clock::now();
        const fs::path out_path = output;
        std::string ext = out_path.extension().string();
        const bool h5 = ext == ".h5" || ext == ".hdf5";
        if (!h5 && ctsurg::surface_export_format(out_path).empty()) {
          throw ctsurg::InputError(output, "suffix", "unknown output format '" + ext + "'; use .h5, .glb, .gltf, .obj, .stl, .ply, .vtk or .vtp");
        }
        if (!std::isfinite(iso)) throw ctsurg::InputError("--iso", "", "must be a finite number");
        if (!*band_opt) pass_band = smooth_method == "sinc" ? 0.01 : 0.1;
        if (!(pass_band > 0.0 && pass_band < 2.0)) {
          throw ctsurg::InputError("--pass-band", "", "must be in (0, 2), got " + fmt::format("{}", pass_band));
        }
        ctsurg::check_output_paths(h5 ? std::vector<fs::path>{out_path, ctsurg::xdmf_path_for(out_path)}
                                      : ctsurg::surface_export_files(out_path, false),
                                   {fs::path(input)});
        Field field = read_field(input);
        if (field.quantity == "HU" && !*iso_opt) {
          throw ctsurg::InputError("--iso", "", input + " is an HU volume: give the isovalue in HU, e.g. --iso 150");
        }
        const auto& g = field.volume.geometry;
        spdlog::info("{}: {} {} x {} x {} nodes, iso {}", input, field.dataset, g.dims[0], g.dims[1], g.dims[2], iso);
        if (decimate > 0 && decimate < 4) throw ctsurg::InputError("--decimate", "", "the target must be at least 4 triangles");
        if (ctsurg::inside_touches_border(field.volume, iso)) {
          if (open_border) {
            spdlog::warn("{}: {} >= {} on the lattice border: the surface is open there (--open-border)", input, field.dataset, iso);
          } else {
            // A frame of nodes below iso closes the surface along the border: the organ is cut there.
            const auto [lo, hi] = std::minmax_element(field.volume.voxels.begin(), field.volume.voxels.end());
            (void)hi;
            const float outside = std::min(*lo, static_cast<float>(iso - 1.0));
            spdlog::warn("{}: {} >= {} on the lattice border: closing the surface there (the lattice gains a one-node frame "
                         "of value {}; --open-border to leave it open)", input, field.dataset, iso, outside);
            field.volume = ctsurg::pad_lattice(field.volume, outside);
          }
        }
        ctsurg::SurfaceMesh mesh = ctsurg::marching_cubes(field.volume, iso, {threads});
        if (mesh.triangle_count() == 0) {
          throw ctsurg::InputError(input, field.dataset,
                                   "no surface at iso " + fmt::format("{}", iso) +
                                       ": every value is on one side of it (nothing to contour)");
        }
        // Coincident vertices (values exactly at iso) and slivers: merged and collapsed, the mesh kept a
        // closed oriented 2-manifold (degenerate_triangles.h). No vertex moves, so the tie stays exact.
        const double cell_mm = ctsurg::lattice_cell_mm(mesh);
        const auto cleanup_start = std::chrono::steady_clock::now();
        const int64_t mc_triangles = mesh.triangle_count();
        const ctsurg::DegenerateRemovalStats cleanup = ctsurg::remove_degenerate_triangles(mesh, cell_mm);
        spdlog::info("degenerate triangles: {} of {} -> {} ({} coincident merges, {} collapses (longest {:.3g} mm), {} flips, "
                     "{} thin handles cut, {} tents removed, {} specks dropped; {:.3f} s)",
                     cleanup.before.summary(), mc_triangles, cleanup.after.total(), cleanup.merged, cleanup.collapsed,
                     cleanup.longest_collapse_mm, cleanup.flipped, cleanup.handles_cut, cleanup.tents_removed,
                     cleanup.dropped_components,
                     std::chrono::duration<double>(std::chrono::steady_clock::now() - cleanup_start).count());
        if (mesh.triangle_count() == 0) {
          throw ctsurg::InputError(input, field.dataset,
                                   "the surface at iso " + fmt::format("{}", iso) + " has no area (only nodes exactly at iso)");
        }
        // Moved vertices can make new slivers; they have left their lattice edges by then, so the
        // cleanup may move them again (relax them towards their one-ring) to remove those.
        const auto clean_again = [&](const char* after) {
          const ctsurg::DegenerateRemovalStats again = ctsurg::remove_degenerate_triangles(mesh, cell_mm, true);
          if (again.before.total() > 0) {
            spdlog::info("degenerate triangles after {}: {} -> {} ({} collapses, {} flips, {} vertices relaxed, {} specks "
                         "dropped)", after, again.before.summary(), again.after.total(), again.collapsed, again.flipped,
                         again.relaxed, again.dropped_components);
            ctsurg::recompute_vertex_normals(mesh);
          }
          return again.before.total() > 0;
        };
        const int s = raw ? 0 : smooth;
        const bool do_decimate = decimate > 0 && decimate < mesh.triangle_count();
        if (s > 0) {
          const auto smooth_start = std::chrono::steady_clock::now();
          const bool closed = ctsurg::is_closed_oriented_surface(mesh);
          const double volume = closed ? ctsurg::enclosed_volume_mm3(mesh) : 0.0;
          if (smooth_method == "sinc") {
            ctsurg::windowed_sinc_smooth(mesh, {s, pass_band});
          } else {
            ctsurg::taubin_smooth(mesh, {s, 0.5, pass_band});
          }
          std::string restored = "open surface: volume not restored";
          if (closed && volume > 0.0) {
            const double smoothed = ctsurg::enclosed_volume_mm3(mesh);
            const double offset = ctsurg::restore_enclosed_volume(mesh, volume);
            restored = fmt::format("volume {:+.3f} % restored by a {:+.4f} mm normal offset",
                                   100.0 * (smoothed / volume - 1.0), offset);
          }
          spdlog::info("smoothed: {} {} iterations, pass band {}; {} ({:.3f} s)",
                       smooth_method == "sinc" ? "windowed-sinc" : "Taubin", s, pass_band, restored,
                       std::chrono::duration<double>(std::chrono::steady_clock::now() - smooth_start).count());
          // Cleaned after the restore (before it, specks and thin parts are still shrunk); the few
          // collapses change the volume slightly, so it is restored once more (a tiny offset).
          if (clean_again("smoothing") && closed && volume > 0.0 && ctsurg::is_closed_oriented_surface(mesh)) {
            ctsurg::restore_enclosed_volume(mesh, volume);
          }
        }
        if (do_decimate) {
          const int64_t before = mesh.triangle_count();
          ctsurg::decimate_surface(mesh, decimate);
          spdlog::info("decimated: {} -> {} triangles", before, mesh.triangle_count());
          clean_again("decimation");
        }
        // The tie follows the moved vertices (marching cubes' tie is exact for --raw).
        if (s > 0 || do_decimate) ctsurg::tie_surface_to_lattice(mesh, field.volume);
        const ctsurg::DegenerateTriangleCount left = ctsurg::count_degenerate_triangles(mesh, cell_mm);
        if (left.total() > 0) {
          spdlog::warn("{} degenerate triangles could not be removed without breaking the surface: {}", left.total(), left.summary());
        }
        mesh.quantity = field.quantity;
        mesh.source_dataset = field.dataset;
        spdlog::info("surface: {} vertices, {} triangles", mesh.vertex_count(), mesh.triangle_count());
        if (h5) {
          ctsurg::Provenance provenance{ctx.name, ctsurg::kVersion, ctx.command_line, {}, nlohmann::json::array()};
          provenance.add_input(input);
          ctsurg::write_surface_mesh_file(out_path, mesh, provenance);
        } else {
          ctsurg::OutputUnit outputs;
          ctsurg::add_surface_export(outputs, out_path, mesh);
          outputs.commit();
        }
        spdlog::info("wrote {} in {:.2f} s", output,
                     std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      });
}
