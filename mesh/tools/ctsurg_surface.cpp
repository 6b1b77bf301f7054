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
  int smooth = 0;
  int64_t decimate = 0;
  bool open_border = false;
  CLI::Option* iso_opt = nullptr;
  return ctsurg::run_tool(
      argc, argv, "ctsurg-surface",
      "Extract the organ surface by marching cubes (closed, consistently oriented, shared vertices, each vertex "
      "tied to its grid cell): from an occupancy grid's volume fractions (default iso 0.5) or an HU volume "
      "(--iso HU). Output by suffix: .h5 (ctsurg surface + XDMF), .glb, .gltf, .obj, .stl, .ply, .vtk, .vtp (3D Slicer: SPACE=LPS); LPS mm.",
      [&](CLI::App& app) {
        app.add_option("input", input, "Occupancy grid (ctsurg-grid) or HU volume (ctsurg-import) file (.h5)")->required();
        app.add_option("output", output, "Surface to write: .h5, .glb, .gltf, .obj, .stl, .ply, .vtk or .vtp")->required();
        iso_opt = app.add_option("--iso", iso, "Isovalue: volume fraction for a grid (default 0.5), HU for an HU volume (required)");
        app.add_option("--threads", threads, "OpenMP threads (0: all)")->check(CLI::Range(0, 1024));
        app.add_option("--smooth", smooth, "Taubin smoothing iterations (lambda 0.5, pass band 0.1; volume-preserving); 0: off")
            ->check(CLI::NonNegativeNumber);
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
        if (smooth > 0 || (decimate > 0 && decimate < mesh.triangle_count())) {
          const int64_t before = mesh.triangle_count();
          if (smooth > 0) ctsurg::taubin_smooth(mesh, {smooth});
          if (decimate > 0) ctsurg::decimate_surface(mesh, decimate);
          ctsurg::tie_surface_to_lattice(mesh, field.volume);
          if (smooth > 0) spdlog::info("smoothed: {} Taubin iterations", smooth);
          if (mesh.triangle_count() < before) spdlog::info("decimated: {} -> {} triangles", before, mesh.triangle_count());
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
