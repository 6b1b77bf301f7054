// ctsurg-tetmesh GRID.h5 OUTPUT: a boundary-conforming Delaunay tetrahedral mesh (CGAL Mesh_3 with
// sliver perturbation and exudation) of the tissue labels in an occupancy grid file, as a ctsurg tet
// mesh file (.h5 + XDMF) or for other programs (.vtu, .msh, .mesh); LPS mm.
// ctsurg-tetmesh --import MESH OUTPUT: a tet mesh from another mesher (.vtu, .msh, .mesh), checked,
// oriented, with boundary faces and the quality report, written the same ways.
#include "ctsurg/core/atomic_output.h"
#include "ctsurg/core/error.h"
#include "ctsurg/core/memory_guard.h"
#include "ctsurg/core/occupancy_grid_file.h"
#include "ctsurg/core/provenance.h"
#include "ctsurg/core/tet_mesh_file.h"
#include "ctsurg/core/tool_app.h"
#include "ctsurg/core/version.h"
#include "ctsurg/core/xdmf_sidecar.h"
#include "ctsurg/mesh/tet_mesh_export.h"
#include "ctsurg/mesh/tet_mesh_import.h"
#include "ctsurg/mesh/tet_mesh_refinement.h"
#include "ctsurg/mesh/tetrahedral_meshing.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>

namespace fs = std::filesystem;

namespace {

// Rough peak memory of Mesh_3 per tet of the final mesh (cells with their cached circumcentres and
// facet data, vertices, the coarse outside cells, the optimisers' copies), bytes.
constexpr uint64_t kBytesPerTet = 1024;

void log_quality(const ctsurg::TetMesh& m, bool from_mask = true) {
  const auto& q = m.quality;
  spdlog::info("tetmesh: {} nodes, {} tets, {} boundary faces", m.node_count(), m.tet_count(), m.boundary_face_count());
  spdlog::info("tetmesh: dihedral angles {:.2f} .. {:.2f} deg; {} slivers (a dihedral angle under {} deg); {} inverted",
               q.min_dihedral_deg, q.max_dihedral_deg, q.slivers, q.sliver_threshold_deg, q.inverted);
  spdlog::info("tetmesh: radius-edge ratio {:.3f} .. {:.3f}, mean {:.3f}", q.min_radius_edge, q.max_radius_edge,
               q.mean_radius_edge);
  std::string hist;
  for (std::size_t b = 0; b < q.radius_edge_histogram.size(); ++b) {
    const bool last = b + 1 == q.radius_edge_histogram.size();
    hist += fmt::format("{}[{:.1f},{}) {}", b ? ", " : "", q.radius_edge_bin_edges[b],
                        last ? std::string("inf") : fmt::format("{:.1f}", q.radius_edge_bin_edges[b + 1]),
                        q.radius_edge_histogram[b]);
  }
  spdlog::info("tetmesh: radius-edge histogram: {}", hist);
  if (!from_mask) {
    spdlog::info("tetmesh: mesh volume {:.1f} mm^3", q.volume_mm3);
    return;
  }
  spdlog::info("tetmesh: mesh volume {:.1f} mm^3 vs mask voxels {:.1f} mm^3 ({:+.2f} %)", q.volume_mm3,
               m.mask_volume_mm3, 100.0 * (q.volume_mm3 - m.mask_volume_mm3) / m.mask_volume_mm3);
}

}  // namespace

int main(int argc, char** argv) {
  std::string input, output, source = "mask", optimiser = "none", labels_text, import_path;
  std::vector<std::string> files;
  ctsurg::TetMeshingOptions options;
  int64_t max_cells = 5'000'000;
  int refine = 0;
  CLI::Option* cell_opt = nullptr;
  CLI::Option* facet_opt = nullptr;
  CLI::Option* distance_opt = nullptr;
  return ctsurg::run_tool(
      argc, argv, "ctsurg-tetmesh",
      "Boundary-conforming Delaunay tetrahedral mesh (CGAL Mesh_3, sliver perturbation and "
      "exudation; fixed seed, deterministic) of the tissue labels of an occupancy grid: the full-resolution "
      "/mask (default) or the /grid/label lattice. Several labels give one subdomain each with conforming "
      "interfaces. Output by suffix: .h5 (ctsurg tet mesh + XDMF), .vtu, .msh (Gmsh 4.1), .mesh (Medit); LPS mm. "
      "Criteria default to the grid's cell size. With --import MESH OUTPUT: a tet mesh from another mesher "
      "(.vtu ascii, .msh Gmsh 2.2/4.1 ASCII, .mesh Medit), checked and reoriented, with boundary faces and quality, "
      "or a ctsurg .h5 tet mesh. --refine N splits every tet into eight N times (nested meshes of one domain).",
      [&](CLI::App& app) {
        app.add_option("files", files, "GRID.h5 (occupancy grid from ctsurg-grid; not with --import) OUTPUT (.h5, .vtu, .msh or .mesh)")
            ->required()
            ->expected(1, 2);
        app.add_option("--import", import_path,
                       "Read this tet mesh instead of meshing a grid: .vtu (ascii arrays), .msh (Gmsh 2.2/4.1 ASCII), "
                       ".mesh (Medit ASCII), or a ctsurg tet mesh (.h5, to refine it); LPS mm");
        app.add_option("--refine", refine,
                       "Split every tet into eight at its edges' midpoints this many times (0 .. 4, default 0): nested "
                       "meshes of the same domain and boundary, 8x the tets each time")
            ->check(CLI::Range(0, 4));
        app.add_option("--source", source, "Labels to mesh: mask (full resolution, default) or grid (/grid/label)")
            ->check(CLI::IsMember({"mask", "grid"}));
        app.add_option("--labels", labels_text, "Comma-separated labels to mesh (default: every non-zero label)");
        cell_opt = app.add_option("--cell-size", options.cell_size_mm, "Max tet circumradius, mm (default: grid cell size)");
        facet_opt = app.add_option("--facet-size", options.facet_size_mm,
                                   "Max boundary-facet circumradius, mm (default: the cell size)");
        distance_opt = app.add_option("--facet-distance", options.facet_distance_mm,
                                      "Max facet-to-surface distance, mm (default: the larger of half a voxel and a quarter of the cell size)");
        app.add_option("--radius-edge", options.radius_edge_ratio, "Max tet circumradius / shortest edge (default 2)");
        app.add_option("--facet-angle", options.facet_angle_deg, "Min boundary-facet angle, degrees (default 25, at most 30)");
        app.add_option("--optimiser", optimiser, "Smoothing before sliver removal: none (default), odt or lloyd")
            ->check(CLI::IsMember({"odt", "lloyd", "none"}));
        app.add_option("--optimiser-iterations", options.optimiser_iterations, "Smoothing iterations (default 20)");
        app.add_option("--sliver-bound", options.sliver_bound_deg,
                       "Perturbation and exudation target: min dihedral angle, degrees (default 12)");
        app.add_option("--max-cells", max_cells, "Refuse when the criteria would give more tets than this (default 5000000)")
            ->check(CLI::PositiveNumber);
        app.add_option("--seed", options.seed, "Random seed (default 0)");
      },
      [&](const ctsurg::ToolContext& ctx) {
        const auto start = std::chrono::steady_clock::now();
        if (import_path.empty() != (files.size() == 2)) {
          throw ctsurg::InputError("files", "", import_path.empty() ? "give GRID.h5 OUTPUT (or --import MESH OUTPUT)"
                                                                    : "with --import give only OUTPUT");
        }
        output = files.back();
        if (files.size() == 2) input = files.front();
        const fs::path out_path = output;
        const std::string ext = out_path.extension().string();
        const bool h5 = ext == ".h5" || ext == ".hdf5";
        if (!h5 && ctsurg::tet_mesh_export_format(out_path).empty()) {
          throw ctsurg::InputError(output, "suffix", "unknown output format '" + ext + "'; use .h5, .vtu, .msh or .mesh");
        }
        options.labels.clear();
        if (!labels_text.empty()) {
          std::size_t pos = 0;
          while (pos <= labels_text.size()) {
            const std::size_t comma = std::min(labels_text.find(',', pos), labels_text.size());
            const std::string item = labels_text.substr(pos, comma - pos);
            char* end = nullptr;
            const long v = std::strtol(item.c_str(), &end, 10);
            if (item.empty() || *end != '\0' || v < 1 || v > 65535) {
              throw ctsurg::InputError("--labels", "", "expected comma-separated labels in 1..65535, got '" + labels_text + "'");
            }
            options.labels.push_back(static_cast<uint16_t>(v));
            pos = comma + 1;
          }
        }
        options.optimiser = optimiser == "odt"     ? ctsurg::TetOptimiser::odt
                            : optimiser == "lloyd" ? ctsurg::TetOptimiser::lloyd
                                                   : ctsurg::TetOptimiser::none;
        const auto write = [&](const ctsurg::TetMesh& meshed, const std::string& source_file) {
          ctsurg::TetMesh refined;
          if (refine > 0) {
            const int64_t tets = meshed.tet_count() << (3 * refine);
            if (tets > max_cells) {
              throw ctsurg::InputError("--refine", "", fmt::format("{} refinements of {} tets give {} tets, over --max-cells {}",
                                                                   refine, meshed.tet_count(), tets, max_cells));
            }
            ctsurg::check_allocation(static_cast<uint64_t>(tets), 250, source_file, fmt::format("--refine {}", refine));
            refined = ctsurg::refine_tet_mesh_uniformly(meshed, refine);
            spdlog::info("refined {} times: {} nodes, {} tets", refine, refined.node_count(), refined.tet_count());
            log_quality(refined, import_path.empty());
          }
          const ctsurg::TetMesh& mesh = refine > 0 ? refined : meshed;
          if (h5) {
            ctsurg::Provenance provenance{ctx.name, ctsurg::kVersion, ctx.command_line, {}, nlohmann::json::array()};
            provenance.add_input(source_file);
            ctsurg::write_tet_mesh_file(out_path, mesh, provenance);
          } else {
            ctsurg::AtomicOutput out(out_path);
            ctsurg::export_tet_mesh(out.temp_path(), mesh, out_path);
            out.commit();
          }
          spdlog::info("wrote {} in {:.2f} s", output,
                       std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
        };
        if (!import_path.empty()) {
          ctsurg::check_output_paths(h5 ? std::vector<fs::path>{out_path, ctsurg::xdmf_path_for(out_path)}
                                        : std::vector<fs::path>{out_path},
                                     {fs::path(import_path)});
          const std::string in_ext = fs::path(import_path).extension().string();
          if (in_ext == ".h5" || in_ext == ".hdf5") {
            const ctsurg::TetMesh mesh = ctsurg::read_tet_mesh_file(import_path);
            spdlog::info("{}: ctsurg tet mesh", import_path);
            log_quality(mesh, false);
            write(mesh, import_path);
            return;
          }
          const ctsurg::TetMeshImport imported = ctsurg::import_tet_mesh(import_path);
          spdlog::info("{}: {} tet mesh", import_path, imported.format);
          if (imported.flipped > 0) {
            spdlog::warn("{}: {} of {} tets were negatively oriented; flipped (two nodes swapped)", import_path,
                         imported.flipped, imported.mesh.tet_count());
          }
          if (imported.unused_nodes > 0) spdlog::warn("{}: {} nodes no tet uses were dropped", import_path, imported.unused_nodes);
          if (imported.skipped_cells > 0) {
            spdlog::info("{}: {} cells that are not 4-node tets skipped", import_path, imported.skipped_cells);
          }
          if (!imported.labels_from_file) spdlog::warn("{}: no label array; every tet is label 1", import_path);
          log_quality(imported.mesh, false);
          write(imported.mesh, import_path);
          return;
        }
        ctsurg::check_output_paths(h5 ? std::vector<fs::path>{out_path, ctsurg::xdmf_path_for(out_path)}
                                      : std::vector<fs::path>{out_path},
                                   {fs::path(input)});
        const ctsurg::OccupancyGrid grid = ctsurg::read_occupancy_grid_file(input);
        const ctsurg::Volume<uint16_t>& lattice = source == "grid" ? grid.label : grid.mask;
        const std::string dataset = source == "grid" ? "/grid/label" : "/mask";
        const auto& g = lattice.geometry;
        const double cell_mm = grid.label.geometry.spacing.maxCoeff();
        if (!*cell_opt) options.cell_size_mm = cell_mm;
        if (!*facet_opt) options.facet_size_mm = options.cell_size_mm;
        if (!*distance_opt) options.facet_distance_mm = std::max(0.5 * g.spacing.maxCoeff(), 0.25 * options.cell_size_mm);
        ctsurg::validate_tet_meshing_options(options);

        // Refuse before meshing when the criteria would give an absurd mesh or not fit in memory.
        const double volume = ctsurg::labelled_volume_mm3(lattice, options.labels);
        const double area = ctsurg::labelled_surface_area_mm2(lattice, options.labels);
        const int64_t estimate = ctsurg::estimate_tet_count(volume, area, options);
        spdlog::info("{}: {} {} x {} x {} voxels, {:.0f} mm^3 labelled; cell size {} mm, facet size {} mm, facet "
                     "distance {} mm: about {} tets expected",
                     input, dataset, g.dims[0], g.dims[1], g.dims[2], volume, options.cell_size_mm,
                     options.facet_size_mm, options.facet_distance_mm, estimate);
        if (volume > 0.0 && estimate > max_cells) {
          throw ctsurg::InputError("--max-cells", "",
                                   fmt::format("the criteria (cell size {} mm, facet size {} mm, facet distance {} mm) "
                                               "would give about {} tets, over the limit of {}; coarsen them or raise "
                                               "--max-cells",
                                               options.cell_size_mm, options.facet_size_mm, options.facet_distance_mm,
                                               estimate, max_cells));
        }
        ctsurg::check_allocation(static_cast<uint64_t>(std::max<int64_t>(estimate, 0)), kBytesPerTet, input,
                                 dataset + " meshed at --cell-size " + fmt::format("{}", options.cell_size_mm));

        ctsurg::TetMesh mesh = ctsurg::tetrahedral_mesh(lattice, options, input + ": " + dataset);
        log_quality(mesh);
        write(mesh, input);
      });
}
